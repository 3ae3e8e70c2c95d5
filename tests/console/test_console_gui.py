"""The control panel's callbacks, driven by assigning handle values (no browser)."""
from __future__ import annotations

import numpy as np
import pytest
import viser

from swarmdeck.console.runtime.loop import ControlLoop, DensityParams, LoopConfig
from swarmdeck.console.web.gui import ConsoleGui, ray_to_floor
from swarmdeck.console.web.scene import ArenaScene


@pytest.fixture(scope="module")
def server():
    s = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield s
    s.stop()


@pytest.fixture
def console(server):
    server.gui.reset()
    server.scene.reset()
    loop = ControlLoop(LoopConfig(seed=2, n_robots=6, density=DensityParams(moving=False)))
    scene = ArenaScene(server, loop.config.bounds)
    gui = ConsoleGui(server, loop, scene)
    frame = loop.tick()
    scene.draw(frame)
    gui.record(frame)
    gui.update(frame, force=True)
    return loop, scene, gui


def test_run_pause_step_and_estop_buttons(console) -> None:
    loop, _, gui = console
    gui.pause_button.value = True
    assert loop.tick().run_state == "paused"
    gui.step_button.value = True
    assert not loop.tick().stopped
    gui.estop_button.value = True
    f = loop.tick()
    assert f.run_state == "estop" and f.stopped
    gui.run_button.value = True
    assert loop.tick().run_state == "estop"
    gui.release_button.value = True
    gui.run_button.value = True
    assert loop.tick().run_state == "running"


def test_behaviour_and_parameters(console) -> None:
    loop, _, gui = console
    gui.behaviour.value = "formation"
    assert loop.tick().behaviour == "formation"
    gui.params["kappa"].value = 2.5
    gui.params["law"].value = "lloyd"
    gui.params["formation_edge"].value = 0.5
    f = loop.tick()
    assert (f.params["kappa"], f.params["law"], f.params["formation_edge"]) == (2.5, "lloyd", 0.5)
    gui.params["gamma"].value = 30.0
    gui.params["safety_distance"].value = 0.2
    f = loop.tick()
    assert f.params["gamma"] == 30.0 and f.barrier.safety_distance == pytest.approx(0.2)


def test_script_loading_reports_errors_and_loads_good_scripts(console, tmp_path) -> None:
    loop, _, gui = console
    gui.script_path.value = str(tmp_path / "nope.py")
    gui.load_script.value = True
    assert loop.behaviour_name == "coverage" and any("does not exist" in m for m in gui.messages)
    good = tmp_path / "good.py"
    good.write_text("import numpy as np\ndef behaviour(poses, t):\n    return np.zeros((len(poses), 2))\n")
    gui.script_path.value = str(good)
    gui.load_script.value = True
    assert loop.tick().behaviour == f"script:{good}"
    assert gui.behaviour.value == f"script:{good}"


def test_barrier_off_needs_confirmation(console) -> None:
    loop, _, gui = console
    gui.barrier_on.value = False
    assert gui.barrier_on.value is True and loop.tick().barrier.enabled  # not yet
    gui.cancel_off.value = True
    assert loop.tick().barrier.enabled
    gui.barrier_on.value = False
    gui.confirm_off.value = True
    f = loop.tick()
    assert not f.barrier.enabled and gui.barrier_on.value is False
    gui.barrier_on.value = True
    assert loop.tick().barrier.enabled


def test_bumps_add_edit_remove(console) -> None:
    loop, _, gui = console
    gui.bump_sigma.value = 0.3
    gui.bump_weight.value = 2.0
    bid = gui.add_bump((0.8, -0.4))
    assert bid is not None and gui.bump_select.value == f"bump {bid}"
    b = loop.bumps.get(bid)
    assert (b.sigma, b.weight) == (0.3, 2.0)
    gui.bump_sigma.value = 0.5
    gui.bump_weight.value = 4.0
    b = loop.bumps.get(bid)
    assert (b.sigma, b.weight) == (0.5, 4.0)
    handle = gui._bump_handles[bid]
    handle.position = (-0.5, 0.25, 0.02)  # as a drag in the browser would
    loop.move_bump(bid, handle.position[:2])
    np.testing.assert_allclose(loop.bumps.get(bid).mu, (-0.5, 0.25))
    assert gui.add_bump((9.0, 9.0)) is None and any("outside the arena" in m for m in gui.messages)
    gui.bump_remove.value = True
    assert loop.bumps.live() == [] and gui.bump_select.value == "none"


def test_layer_toggles(console) -> None:
    _, scene, gui = console
    gui.layers["voronoi"].value = False
    assert scene.visible["voronoi"] is False and scene.nodes.voronoi.visible is False
    gui.layers["voronoi"].value = True
    assert scene.nodes.voronoi.visible is True
    gui.layers["labels"].value = False
    assert all(not lab.visible for lab in scene.nodes.labels)


def test_status_line_and_alerts(console) -> None:
    loop, _, gui = console
    loop.estop()
    f = loop.tick()
    gui.record(f)
    gui.update(f, force=True)
    assert "EMERGENCY STOP" in gui.status.content and "N = 6" in gui.status.content


def test_ray_to_floor() -> None:
    assert ray_to_floor((0.0, 0.0, 6.0), (0.1, -0.05, -1.0)) == pytest.approx((0.6, -0.3))
    assert ray_to_floor((0.0, 0.0, 6.0), (1.0, 0.0, 0.0)) is None
    assert ray_to_floor((0.0, 0.0, 6.0), (0.0, 0.0, 1.0)) is None


def test_shift_click_sends_the_robots_there(console) -> None:
    loop, _, gui = console
    gui.go_to((1.2, -0.6))
    assert loop.behaviour_name == "goto" and loop.behaviour_params.goal_centre == (1.2, -0.6)
    f = loop.tick()
    # every robot heads for a goal near the clicked point (the cluster is pushed inside the arena)
    from swarmdeck.console.runtime.behaviours import cluster_goals

    goals = cluster_goals(f.n, (1.2, -0.6), loop.config.bounds)
    assert np.linalg.norm(goals.mean(axis=0) - (1.2, -0.6)) < 0.3
    assert np.all(goals[:, 0] <= 1.6 - 0.15 + 1e-9) and np.all(goals[:, 1] >= -1.0 + 0.15 - 1e-9)
    assert len({tuple(np.round(g, 6)) for g in goals}) == f.n
    heading = goals - f.points
    cosine = np.sum(heading * f.nominal, axis=1) / (np.linalg.norm(heading, axis=1) * np.linalg.norm(f.nominal, axis=1))
    assert np.all(cosine > 0.999)
    gui.go_to((5.0, 0.0))
    assert any("outside the arena" in m for m in gui.messages)
