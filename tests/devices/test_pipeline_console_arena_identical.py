"""One pipeline for a tick's commands: the console loop and Arena.step drive robots bit-identically.

Same poses and nominal velocities through ``ControlLoop.tick`` (the console, ``swarmdeck console``)
and ``Arena.step`` (``swarmdeck run``, the rps facade) give the same wheel commands, bit for bit,
with the barrier binding and wheels saturating; unseen robots and the sink's obstacles are fixed
obstacles of the barrier exactly as a direct filter call over the seen robots says; a failing
filter stops every robot through both.
"""
from __future__ import annotations

import numpy as np

from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.devices import Arena, ArenaConfig, GritsBotParams, lookahead_points, unicycle_to_wheels
from swarmdeck.devices.pipeline import barrier_filter, certify
from swarmdeck.devices.simulated_robots import SimulatedRobots
from swarmdeck.safety import UnicycleSafetyFilter

# The nominal both drivers get: look-ahead points to a common goal, at most 0.15 m/s (inside the
# console's max_speed, so its saturation leaves it untouched bit for bit).
NOMINAL = """
import numpy as np

def behaviour(poses, t):
    p = poses[:, :2] + 0.03 * np.column_stack((np.cos(poses[:, 2]), np.sin(poses[:, 2])))
    u = 0.8 * (np.array([0.3, -0.1]) - p)
    n = np.linalg.norm(u, axis=1, keepdims=True)
    return np.where(n > 0.15, u * (0.15 / np.maximum(n, 1e-300)), u)
"""


def nominal_fn():
    scope: dict = {}
    exec(NOMINAL, scope)
    return scope["behaviour"]


def ring(n: int = 6) -> np.ndarray:
    """Robots on a circle of radius 0.25 m around the goal, heading tangentially (they must turn)."""
    a = np.linspace(0, 2 * np.pi, n, endpoint=False)
    return np.column_stack((0.3 + 0.25 * np.cos(a), -0.1 + 0.25 * np.sin(a), a + np.pi / 2))


def console(tmp_path, robots, source=None) -> ControlLoop:
    script = tmp_path / "nominal.py"
    script.write_text(NOMINAL)
    return ControlLoop(LoopConfig(n_robots=robots.n_robots, behaviour=f"script:{script}", script_budget=0.5),
                       source=source if source is not None else robots, sink=robots)


def test_console_and_arena_send_bit_identical_wheel_commands(tmp_path) -> None:
    poses0 = ring()
    robots = SimulatedRobots(6, ArenaConfig(), initial_poses=poses0)
    loop = console(tmp_path, robots)
    arena = Arena(initial_conditions=poses0, config=ArenaConfig())
    fn = nominal_fn()
    changed = 0
    for _ in range(40):
        np.testing.assert_array_equal(robots.sim.poses, arena.poses())
        arena.set_velocities(fn(arena.poses(), arena.time))
        arena.step()
        frame = loop.tick()
        for a, b in zip(unicycle_to_wheels(frame.v, frame.w, GritsBotParams()),
                        unicycle_to_wheels(*arena.backend.applied, GritsBotParams())):
            np.testing.assert_array_equal(a, b)
        np.testing.assert_array_equal(robots.sim.applied[0], arena.backend.applied[0])
        np.testing.assert_array_equal(frame.safe, arena.last_safe)
        changed += int(frame.barrier.n_active > 0)
    np.testing.assert_array_equal(robots.sim.poses, arena.poses())
    # the case is not vacuous: the barrier bound and the wheel limits scaled commands down
    assert changed > 0 and arena.safety_stats.interventions > 0 and arena.safety_stats.saturations > 0
    assert not frame.alerts and arena.safety_stats.failures == 0


class _Blind:
    """A pose source that reports some robots unseen (as a camera does when a tag is hidden)."""

    name = "blind"

    def __init__(self, inner: SimulatedRobots, hidden: list[int]) -> None:
        self.inner, self.hidden = inner, hidden

    def read(self, now: float):
        r = self.inner.read(now)
        seen = r.seen.copy()
        seen[self.hidden] = False
        return type(r)(r.ids, r.poses, seen)

    def health(self) -> str:
        return "ok"


class _WithObstacles(SimulatedRobots):
    """Simulated robots whose sink also reports fixed obstacles (robots excluded from control)."""

    def __init__(self, *args, obstacles: np.ndarray, **kw) -> None:
        super().__init__(*args, **kw)
        self._obstacles = obstacles

    def obstacles(self) -> np.ndarray:
        return self._obstacles.copy()


def test_unseen_robots_and_obstacles_are_fixed_obstacles(tmp_path) -> None:
    poses0 = ring()
    extra = np.array([[0.3, -0.1]])  # an excluded robot at the goal
    robots = _WithObstacles(6, ArenaConfig(), initial_poses=poses0, obstacles=extra)
    hidden = [1, 4]
    loop = console(tmp_path, robots, source=_Blind(robots, hidden))
    robot = GritsBotParams()
    reference = barrier_filter(robot, (-1.6, 1.6, -1.0, 1.0), 0.033, max_speed=0.2)  # Arena's default filter
    seen = np.ones(6, dtype=bool)
    seen[hidden] = False
    fn = nominal_fn()
    bound = 0
    for _ in range(25):
        poses = robots.sim.poses
        frame = loop.tick()
        nominal = np.where(seen[:, None], fn(poses, 0.0), 0.0)
        np.testing.assert_array_equal(frame.nominal, nominal)
        # the pipeline as Arena.step calls it, with the console's seen mask and obstacles
        cert = certify(poses, nominal, robot, reference, seen=seen, obstacles=extra)
        np.testing.assert_array_equal(frame.v, cert.v)
        np.testing.assert_array_equal(frame.w, cert.w)
        # and independently: the barrier over the seen robots, the unseen ones' points as obstacles
        idx = np.flatnonzero(seen)
        obstacles = np.concatenate((lookahead_points(poses, robot.lookahead)[~seen], extra))
        v0, w0 = cert.v_nominal[idx], cert.w_nominal[idx]
        vs, ws, diag = reference.filter(poses[idx], v0, w0, obstacles)
        np.testing.assert_array_equal(frame.v[idx], vs)
        np.testing.assert_array_equal(frame.w[idx], ws)
        assert np.all(frame.v[~seen] == 0.0) and np.all(frame.w[~seen] == 0.0)
        np.testing.assert_array_equal(frame.barrier.intervention[idx], diag.intervention)
        assert np.all(frame.barrier.intervention[~seen] == 0.0)
        assert np.all(np.isin(frame.barrier.active_pairs, idx))  # pairs in all-N indices, among seen robots
        bound += diag.n_active > 0
    assert bound > 0


class _Broken(UnicycleSafetyFilter):
    """A barrier whose solver hands back a NaN for one robot (a defect that must stop everybody)."""

    def filter(self, poses, v, w, obstacles=None):
        vs, ws, diag = super().filter(poses, v, w, obstacles)
        vs = np.array(vs)
        vs[0] = np.nan
        return vs, ws, diag


def test_a_failing_filter_stops_every_robot_through_both(tmp_path) -> None:
    poses0 = ring()
    robots = SimulatedRobots(6, ArenaConfig(), initial_poses=poses0)
    loop = console(tmp_path, robots)
    loop._filter = _Broken()  # what set_safety would build, with the defect
    arena = Arena(initial_conditions=poses0, config=ArenaConfig(), safety=_Broken())
    arena.set_velocities(nominal_fn()(arena.poses(), 0.0))
    arena.step()
    frame = loop.tick()
    assert np.all(frame.v == 0.0) and np.all(frame.w == 0.0) and np.all(frame.safe == 0.0)
    np.testing.assert_array_equal(arena.backend.applied[0], np.zeros(6))
    np.testing.assert_array_equal(arena.backend.applied[1], np.zeros(6))
    status = "filter returned the wrong shape or non-finite values for 6 robots"
    assert f"safety filter: {status}; robots stopped" in frame.alerts and not frame.barrier.ok
    assert arena.safety_stats.failures == 1 and arena.safety_stats.failure_reasons == {status: 1}
    np.testing.assert_array_equal(robots.sim.poses, arena.poses())
