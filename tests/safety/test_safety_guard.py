"""The guard of a bypassed barrier (swarmdeck.safety.guard) in the control loop: whatever a script commands with the
barrier switched off — open-loop drives, or a two-faced script that holds still and looks for pose jitter before it
chases the others — no pair of look-ahead points ever comes closer than the guard distance and no robot leaves the
arena; the guard's pieces on their own: the closest approach over a tick, the trip rules, the brake."""
import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.spatial.distance import pdist

from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.devices import ArenaConfig
from swarmdeck.devices.simulated_robots import SimulatedRobots
from swarmdeck.safety import BarrierConfig
from swarmdeck.safety.guard import GuardConfig, approaches, brake, check

BOUNDS = (-0.7, 0.7, -0.5, 0.5)  # a small floor: robots meet often
GUARD = GuardConfig()


class Script:
    """A user's experiment as the loop's behaviour: nominal look-ahead velocities (N, 2), m/s."""

    name = "script (test)"

    def __init__(self, kind: str, seed: int) -> None:
        self.kind, self.rng, self.seen, self.ticks = kind, np.random.default_rng(seed), [], 0
        self.plan = None

    def __call__(self, tick):
        n, self.ticks = len(tick.points), self.ticks + 1
        if self.kind == "open-loop":  # piecewise-constant random drives, full speed, every 20 ticks a new one
            if self.plan is None or self.ticks % 20 == 0:
                angle = self.rng.uniform(-np.pi, np.pi, n)
                self.plan = tick.max_speed * np.column_stack((np.cos(angle), np.sin(angle)))
            return self.plan.copy(), None
        if self.ticks <= 8:  # two-faced: hold still and look for the tracking noise of verification
            self.seen.append(tick.poses.copy())
            return np.zeros((n, 2)), None
        if float(np.max(np.abs(np.diff(np.array(self.seen), axis=0)))) > 1e-5:
            return np.zeros((n, 2)), None  # watched: behave
        p = tick.points
        if self.kind == "chase":  # each robot at full speed at its nearest neighbour
            d = np.linalg.norm(p[:, None] - p[None], axis=2) + np.eye(n) * 1e9
            to = p[np.argmin(d, axis=1)] - p
        else:  # "swap": everyone through the centre to the opposite side
            to = -2 * p
        norm = np.maximum(np.linalg.norm(to, axis=1, keepdims=True), 1e-9)
        return tick.max_speed * to / norm, None


@settings(max_examples=30, deadline=None)
@given(n=st.integers(2, 6), seed=st.integers(0, 2**31 - 1), kind=st.sampled_from(["open-loop", "chase", "swap"]))
def test_no_pair_below_the_guard_distance_and_no_robot_outside_whatever_the_script_does(n, seed, kind):
    robots = SimulatedRobots(n, ArenaConfig(bounds=BOUNDS, seed=seed))
    loop = ControlLoop(LoopConfig(n_robots=n, bounds=BOUNDS, seed=seed), source=robots, sink=robots)
    start = loop.tick()
    assume(n < 2 or pdist(start.poses[:, :2] + 0.03 * np.column_stack(
        (np.cos(start.poses[:, 2]), np.sin(start.poses[:, 2])))).min() >= GUARD.guard_distance)
    loop.use_behaviour(Script(kind, seed))
    loop.set_safety(enabled=False)
    for _ in range(90):
        f = loop.tick()
        points = f.poses[:, :2] + f.lookahead * np.column_stack((np.cos(f.poses[:, 2]), np.sin(f.poses[:, 2])))
        assert pdist(points).min() >= GUARD.guard_distance - 1e-9
        x0, x1, y0, y1 = BOUNDS
        assert np.all((f.poses[:, 0] > x0) & (f.poses[:, 0] < x1) & (f.poses[:, 1] > y0) & (f.poses[:, 1] < y1))
    assert loop.contacts.episodes == []


def test_a_head_on_attack_revokes_the_bypass_once_and_the_barrier_stays_on():
    poses = np.array([[-0.35, 0.0, 0.0], [0.35, 0.0, np.pi]])
    robots = SimulatedRobots(2, ArenaConfig(), initial_poses=poses)
    loop = ControlLoop(LoopConfig(n_robots=2), source=robots, sink=robots)
    loop.use_behaviour(Script("swap", 0))
    loop.set_safety(enabled=False)
    frames = [loop.tick() for _ in range(120)]
    assert len(loop.revocations) == 1 and loop.revocations[0]["tick"] > 8
    on = [f.barrier.enabled for f in frames]
    assert on[:9] == [False] * 9 and on[-1] and on == sorted(on)
    assert "BARRIER BACK ON" in frames[loop.revocations[0]["tick"]].events[0]
    assert min(f.barrier.min_distance for f in frames) >= GUARD.guard_distance - 1e-9


def test_walls_and_obstacles_stay_hard_without_pair_rows():
    from swarmdeck.safety import SafetyFilter

    walls = SafetyFilter(BarrierConfig(pairs=False))
    points = np.array([[1.5, 0.0], [1.36, 0.0], [0.0, 0.0]])
    u = np.array([[0.2, 0.0], [0.2, 0.0], [0.2, 0.0]])  # the first two at the +x wall, the third at an obstacle
    safe, diag = walls.filter(points, u, obstacles=np.array([[0.2, 0.0]]))
    assert diag.ok and safe[0, 0] < 0.2 and safe[2, 0] < 0.2  # wall and obstacle rows bind
    with pytest.raises(ValueError, match="pairs must be true or false"):
        BarrierConfig(pairs="no")


def test_closest_approach_over_a_tick_and_the_trip_rules():
    p0 = np.array([[0.0, 0.0], [0.4, 0.0], [5.0, 5.0]])
    p1 = np.array([[0.2, 0.0], [0.2, 0.0], [5.0, 5.0]])  # the first two meet in the middle
    pairs, closest, now = approaches(p0, p1, 0.15)
    assert pairs.tolist() == [[0, 1]] and closest[0] == pytest.approx(0.0) and now[0] == pytest.approx(0.4)
    tripped = check(GUARD, p0, p1, np.zeros(3), names=np.array([7, 8, 9]))
    assert tripped.trip and tripped.pair == (7, 8) and "robots 7 and 8" in tripped.reason
    calm = check(GUARD, p0, p0, np.array([0.0, 0.09, 0.0]))
    assert not calm.trip and calm.reason is None
    pushy = check(GUARD, p0, p0, np.array([0.0, 0.11, 0.0]))
    assert pushy.trip and "robot 1's command by 0.110 m/s" in pushy.reason
    blind = check(GUARD, p0, p0, np.zeros(3), monitor_ok=False, monitor_status="failed: infeasible")
    assert blind.trip and "could not be evaluated" in blind.reason
    with pytest.raises(ValueError, match="guard_distance"):
        GuardConfig(guard_distance=float("nan"))


def test_the_brake_stops_exactly_who_would_come_too_close():
    p0 = np.array([[0.0, 0.0], [0.3, 0.0], [1.0, 0.0], [1.16, 0.0]])
    p1 = p0 + np.array([[0.1, 0.0], [-0.1, 0.0], [0.0, 0.1], [0.05, 0.0]])  # 0, 1 meet; 2, 3 part
    assert brake(p0, p1, 0.15).tolist() == [True, True, False, False]
    # a robot stopped in front of a follower stops the follower too (chains are followed)
    p0 = np.array([[0.0, 0.0], [0.16, 0.0], [0.5, 0.0]])
    p1 = p0 + np.array([[0.02, 0.0], [0.02, 0.0], [-0.2, 0.0]])
    assert brake(p0, p1, 0.15).tolist() == [True, True, True]
    # fixed points (docked robots) never move and are approached by nobody
    assert brake(np.array([[0.0, 0.0]]), np.array([[0.05, 0.0]]), 0.15, fixed=np.array([[0.19, 0.0]])).tolist() == [True]
    # pairs already closer than the guard distance may part, not approach
    p0 = np.array([[0.0, 0.0], [0.1, 0.0]])
    assert brake(p0, p0 + [[-0.01, 0.0], [0.01, 0.0]], 0.15).tolist() == [False, False]
    assert brake(p0, p0 + [[0.01, 0.0], [0.0, 0.0]], 0.15).tolist() == [True, True]
