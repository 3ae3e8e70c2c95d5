"""Validation counts match hand-built collision, boundary and actuator cases (rps rules)."""
import numpy as np

from swarmdeck.devices import ArenaConfig, SimulatedArena, colliding_pairs, out_of_bounds


def test_collision_uses_shifted_centres():
    # Facing each other 0.18 m apart: shifted centres are 0.13 m apart -> collision.
    facing = np.array([[0.0, 0.0, 0.0], [0.18, 0.0, np.pi]])
    assert colliding_pairs(facing).tolist() == [[0, 1]]
    # Back to back at the same distance: shifted centres 0.23 m apart -> no collision.
    back = np.array([[0.0, 0.0, np.pi], [0.18, 0.0, 0.0]])
    assert len(colliding_pairs(back)) == 0


def test_boundary_is_centre_outside_rectangle():
    poses = np.array([[1.59, 0.0, 0.0], [1.61, 0.0, 0.0], [0.0, -1.01, 0.0], [0.0, 0.99, 0.0]])
    assert out_of_bounds(poses, (-1.6, 1.6, -1.0, 1.0)).tolist() == [False, True, True, False]


def test_counts_per_robot_and_per_step():
    start = np.array([[-0.3, 0.0, 0.0], [0.3, 0.0, np.pi], [1.005, 0.5, 0.0]])
    sim = SimulatedArena(initial_poses=start, config=ArenaConfig(dt=0.1))
    v = np.array([0.2, 0.2, 0.2])
    w = np.zeros(3)
    for _ in range(20):
        sim.step(v, w)
    rep = sim.report
    # Robots 0 and 1 drive at each other (and through each other: the simulator does not
    # stop them) at 0.2 m/s each; the shifted gap 0.55 - 0.04 k is within 0.135 m for
    # steps k = 11 ... 17.
    assert rep.steps_with_collision == 7
    assert rep.collisions_per_robot.tolist() == [7, 7, 0]
    # Robot 2 leaves through x = 1.6 after 3 s... not within 2 s: no boundary errors yet.
    assert rep.steps_with_boundary == 0
    for _ in range(20):
        sim.step(np.array([0.0, 0.0, 0.2]), w)
    # Robot 2 is at x = 1.005 + 0.4 + 0.02 k > 1.6 for k >= 10 of the new 20 steps.
    assert rep.boundary_per_robot.tolist() == [0, 0, 11]
    assert rep.steps == 40
    assert rep.verdict(declared_duration=10.0) == []


def test_actuator_saturation_and_invalid_commands_counted():
    sim = SimulatedArena(initial_poses=np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]))
    sim.step(np.array([1.0, np.nan]), np.array([0.0, 0.0]))
    assert sim.report.actuator_per_robot.tolist() == [1, 0]
    assert sim.report.invalid_command_per_robot.tolist() == [0, 1]
    v, w = sim.applied
    assert v[0] == 0.2 and v[1] == 0.0 and np.all(np.isfinite(sim.poses))


def test_verdict_rejects_like_the_robotarium():
    sim = SimulatedArena(initial_poses=np.array([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0]]))
    for _ in range(101):
        sim.step(np.zeros(2), np.zeros(2))
    reasons = sim.report.verdict(declared_duration=2.0)
    assert any("too close" in r for r in reasons) and any("exceeds" in r for r in reasons)
