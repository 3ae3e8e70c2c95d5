"""rps 2.x's constructor and figure under the facade: every 2.x argument is taken, a flag that is not a bool is
refused as rps 2.x refuses it, an argument swarmdeck does not take is refused naming it and what to use instead,
and the 2.x figure handles (``_fig``, ``_axes_handle``) work headless (issue 28 item 4)."""
from __future__ import annotations

import numpy as np
import pytest

from swarmdeck.devices.rps import rps_aliases


@pytest.fixture
def robotarium():
    with rps_aliases():
        import rps.robotarium as robotarium

        yield robotarium.Robotarium


def test_every_2x_argument_is_taken(robotarium):
    ic = np.array([[0.0, 0.5], [0.0, 0.0], [0.0, np.pi]])
    r = robotarium(number_of_robots=2, show_figure=True, initial_conditions=ic, sim_in_real_time=False,
                   use_distance_sensors=False, obstacles=None, skip_initialization=True, show_arena_boundaries=False,
                   show_robot_patches=True, show_distance_endpoints=False, show_distance_rays=True, show_obstacles=False)
    assert r.number_of_robots == 2 and np.array_equal(r.get_poses(), ic)
    assert r.show_flags == {"show_arena_boundaries": False, "show_robot_patches": True, "show_distance_endpoints": False,
                            "show_distance_rays": True, "show_obstacles": False}
    assert r.obstacles is None and r.skip_initialization
    assert robotarium(number_of_robots=1, obstacles=np.zeros((0, 2, 2))).obstacles.shape == (0, 2, 2)


@pytest.mark.parametrize("kwargs, named, instead", [
    ({"robot_type": "gternal"}, "'robot_type'", "robot_model="),
    ({"boundaries": [-1, 1, -1, 1]}, "'boundaries'", "[console] bounds"),
    ({"initial_condition": np.zeros((3, 2))}, "'initial_condition'", "did you mean 'initial_conditions'"),
    ({"show_robots": True}, "'show_robots'", "did you mean 'show_robot_patches'"),
])
def test_an_argument_swarmdeck_does_not_take_is_named_with_what_to_use(robotarium, kwargs, named, instead):
    with pytest.raises(TypeError) as info:
        robotarium(number_of_robots=2, **kwargs)
    assert named in str(info.value) and instead in str(info.value)


@pytest.mark.parametrize("flag", ["show_figure", "sim_in_real_time", "skip_initialization", "show_obstacles",
                                  "use_distance_sensors"])
def test_a_flag_that_is_not_a_bool_is_refused_as_rps_2x_does(robotarium, flag):
    with pytest.raises(TypeError, match=rf"Robotarium\(\): {flag} must be True or False .*got 'yes'"):
        robotarium(number_of_robots=2, **{flag: "yes"})


@pytest.mark.parametrize("obstacles, match", [
    (np.zeros((2, 2)), r"obstacles must have shape \(M, 2, 2\).*got shape \(2, 2\)"),
    (np.array([[[0.0, 0.0], [np.nan, 1.0]]]), r"obstacles\[0\] has a NaN"),
    ([[[0.0, 0.0], [1.0, np.inf]], [[0.0, 0.0], [1.0, 1.0]]], r"obstacles\[0\] has a NaN or infinite"),
    ("walls", r"obstacles must have shape \(M, 2, 2\).*'walls'"),
])
def test_bad_obstacles_are_named(robotarium, obstacles, match):
    with pytest.raises(ValueError, match=match):
        robotarium(number_of_robots=2, obstacles=obstacles)


def test_more_robots_than_rps_simulates_are_refused(robotarium):
    with pytest.raises(ValueError, match=r"number_of_robots=51: rps simulates at most 50"):
        robotarium(number_of_robots=51)


def test_initialize_says_the_robots_are_there_already(robotarium):
    r = robotarium(number_of_robots=2)
    with pytest.raises(RuntimeError, match=r"initial conditions already.*--from-docks"):
        r.initialize(r.initial_conditions)


def test_2x_figure_handles_work_headless(robotarium):
    r = robotarium(number_of_robots=3)
    fig, ax = r._fig, r._axes_handle
    assert fig is r.figure and ax is r.axes
    marker = ax.scatter([0.0], [0.0], s=20)
    text = ax.text(0, -0.5, "...INITIALIZING...")
    cid = fig.canvas.mpl_connect("resize_event", lambda event: None)
    fig.canvas.draw_idle()
    fig.canvas.flush_events()
    text.remove()
    assert isinstance(cid, int) and marker in ax.collections
    assert r.robot_colormap()(0)[3] == 1.0


def test_solve_qp_projects_onto_the_constraints_as_rps_2x():
    with rps_aliases():
        from rps.utilities.barrier_certificates import _solve_qp

    vhat = np.array([[0.2, 0.0], [0.1, -0.1]])  # (2, N = 2), stacked column by column as rps does
    a = np.zeros((1, 4))
    a[0, 0] = 1.0  # robot 0's x velocity ≤ 0.05
    v = _solve_qp(2, vhat, a, np.array([0.05]))
    assert v.shape == (2, 2)
    assert v == pytest.approx(np.array([[0.05, 0.0], [0.1, -0.1]]), abs=1e-6)
    infeasible = np.array([[1.0, 0, 0, 0], [-1.0, 0, 0, 0]])
    assert _solve_qp(2, vhat, infeasible, np.array([-1.0, -1.0])) is None  # x ≤ −1 and x ≥ 1: rps returns None
