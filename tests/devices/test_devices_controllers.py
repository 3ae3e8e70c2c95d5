"""Every go-to-goal controller converges from random starts (no safety filter: one robot each)."""
import numpy as np
import pytest

from swarmdeck.devices import Arena, ArenaConfig, wrap_angle


def _single(rng, goal_heading=True):
    start = np.array([[rng.uniform(-1.2, 1.2), rng.uniform(-0.7, 0.7), rng.uniform(-np.pi, np.pi)]])
    goal = np.array([[rng.uniform(-1.2, 1.2), rng.uniform(-0.7, 0.7), rng.uniform(-np.pi, np.pi)]])
    return start, goal


@pytest.mark.parametrize("controller", ["si", "clf", "pose", "hybrid"])
def test_converges_from_random_starts(controller):
    rng = np.random.default_rng(7)
    for trial in range(5):
        start, goal = _single(rng)
        arena = Arena(initial_conditions=start, safety=False)
        width = 3 if controller in ("pose", "hybrid") else 2
        arena.set_goals(goal[:, :width], controller=controller)
        for _ in range(1500):
            arena.step()
        p = arena.positions() if controller == "si" else arena.poses()[:, :2]
        assert np.linalg.norm(p[0] - goal[0, :2]) < 0.03, (controller, trial)
        if controller in ("pose", "hybrid"):
            assert abs(wrap_angle(arena.poses()[0, 2] - goal[0, 2])) < 0.1, (controller, trial)


def test_waypoints_visited_in_order():
    arena = Arena(initial_conditions=np.array([[0.0, 0.0, 0.0]]), safety=False)
    square = np.array([[0.5, 0.0], [0.5, 0.5], [0.0, 0.5], [0.0, 0.0]])
    arena.set_waypoints([square], tolerance=0.03)
    visited = []
    for _ in range(1500):
        arena.step()
        k = int(arena.waypoint_index[0])
        if not visited or visited[-1] != k:
            visited.append(k)
    assert visited == [0, 1, 2, 3]
    assert np.linalg.norm(arena.positions()[0] - square[-1]) < 0.03


def test_next_position_commands_track_a_path():
    arena = Arena(initial_conditions=np.array([[0.0, 0.0, 0.0]]), safety=False, config=ArenaConfig())
    p0 = arena.positions()[0]
    for k in range(1, 200):
        target = p0 + np.array([0.003 * k, 0.001 * k])  # 0.09 m/s, well inside the limits
        arena.set_next_positions(target[None, :])
        arena.step()
    assert np.linalg.norm(arena.positions()[0] - target) < 0.01


def test_setting_the_same_goals_every_step_changes_nothing():
    """rps-style loops call set_goals every step: that must not reset the hybrid controller's phase
    (robots the barrier pushes out of their goal must not switch phase differently)."""
    n = 6
    once = Arena(n, config=ArenaConfig(seed=2))
    every = Arena(n, config=ArenaConfig(seed=2))
    goals = np.column_stack((np.full(n, 0.0) + 0.12 * np.arange(n) - 0.3, np.zeros(n), np.linspace(-3, 3, n)))
    once.set_goals(goals, controller="hybrid")
    for _ in range(900):
        once.step()
        every.set_goals(goals.copy(), controller="hybrid")
        every.step()
    assert np.array_equal(once.poses(), every.poses())


def test_setting_the_same_waypoints_every_step_keeps_progress():
    arena = Arena(initial_conditions=np.array([[0.0, 0.0, 0.0]]), safety=False)
    square = np.array([[0.5, 0.0], [0.5, 0.5], [0.0, 0.5], [0.0, 0.0]])
    for _ in range(1500):
        arena.set_waypoints([square.copy()], tolerance=0.03)
        arena.step()
    assert arena.waypoint_index[0] == 3
    assert np.linalg.norm(arena.positions()[0] - square[-1]) < 0.03
    arena.set_waypoints([square[::-1].copy()], tolerance=0.03)  # different lists start over
    assert arena.waypoint_index[0] == 0
