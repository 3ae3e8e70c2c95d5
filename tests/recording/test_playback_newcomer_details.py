"""What a newcomer met in `info`, the player, the plots, the scene and `export --html`: every behaviour change
listed; the player's event list and timeline marks, its slider at 0.01 s; H(t) outside coverage a note, not a
blank chart; no hidden placeholder dot when a point layer is empty; the HTML export quiet and centred."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import viser

from swarmdeck.console.cli import main as cli
from swarmdeck.console.cli.info import summarise
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.recording.recorder import Recorder
from swarmdeck.console.runtime.frame import ContactsFrame
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.console.web.export_html import export_html
from swarmdeck.console.web.plots import PlotHistory, PlotsPanel
from swarmdeck.console.web.scene import ArenaScene

SEQUENCE = ["goto", "rendezvous", "coverage", "formation"]


@pytest.fixture(scope="module")
def session(tmp_path_factory):
    """coverage, then goto, rendezvous, coverage, formation (10 ticks each), with a script error repeated."""
    path = tmp_path_factory.mktemp("newcomer") / "s.mcap"
    loop = ControlLoop(LoopConfig(n_robots=5, seed=3))
    with Recorder(path, {"config": {}}) as rec:
        for name in [None] + SEQUENCE:
            if name is not None:
                loop.set_behaviour(name)
            for k in range(10):
                if name == "rendezvous" and k < 4:
                    loop.post(f"retry {k}")
                rec.write_frame(loop.tick())
    loop.close()
    return path


def test_info_lists_every_behaviour_change(session, capsys):
    s = summarise(str(session))
    assert [c["behaviour"] for c in s["behaviour_changes"]] == ["coverage"] + SEQUENCE
    assert s["behaviour_changes"][0]["t"] == 0.0 and s["behaviour_changes"][2]["t"] > s["behaviour_changes"][1]["t"]
    assert cli(["info", str(session)]) == 0
    line = next(x for x in capsys.readouterr().out.splitlines() if x.strip().startswith("behaviour"))
    assert line.split()[1:2] == ["coverage,"] and all(name in line for name in SEQUENCE)


@pytest.fixture(scope="module")
def player_app(session):
    from swarmdeck.console.web.player import PlayerApp

    with open_recording(session) as rec:
        app = PlayerApp(rec, port=0)
        yield app
        app.server.stop()


def test_the_player_lists_the_events_marks_them_and_seeks_to_them(player_app):
    app = player_app
    texts = [text for _, text, _ in app.event_rows]
    assert "behaviour: goto" in texts and "behaviour: formation" in texts
    assert "retry 3" in texts and texts.count("retry 3") == 1  # four "retry k" lines collapse into one
    assert next(n for _, t, n in app.event_rows if t == "retry 3") == 4
    marks = app.slider._impl.props._marks  # viser keeps them in the props only
    assert marks and len(marks) == len(app.event_rows)
    assert "behaviour: goto" in app.event_list.content and "× 4" in app.event_list.content
    goto = next(o for o in app.event_select.options if o.endswith("behaviour: goto"))
    app.event_select.value = goto
    assert app.player.frame.behaviour == "goto" and "behaviour: goto" in app.player.frame.events  # its frame


def test_the_slider_shows_hundredths(player_app):
    app = player_app
    assert app.slider.step == 0.01
    app.player.seek(0.7)
    app.refresh()
    assert app.slider.value == round(app.player.frame_time, 2) and len(repr(app.slider.value)) <= 5


def test_h_outside_coverage_is_a_note_not_a_blank_chart():
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        panel = PlotsPanel(server.gui)
        hist = PlotHistory()
        loop = ControlLoop(LoopConfig(n_robots=4, seed=1, behaviour="goto"))
        for k in range(5):
            hist.add(k * 0.033, loop.tick())
        panel.show(hist)
        assert not panel.H.visible and panel.H_note.visible and "coverage" in panel.H_note.content
        loop.set_behaviour("coverage")
        hist.add(1.0, loop.tick())
        panel.show(hist)
        assert panel.H.visible and not panel.H_note.visible
        loop.close()
    finally:
        server.stop()


def test_an_empty_point_layer_is_hidden_not_parked_under_the_floor():
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        scene = ArenaScene(server)
        loop = ControlLoop(LoopConfig(n_robots=4, seed=1, behaviour="goto"))
        frame = loop.tick()
        scene.set_layer("density", False)  # nothing covers what lies below the floor any more
        scene.draw(frame)
        assert not scene.nodes.contacts.visible and not scene.nodes.centroids.visible
        touched = dataclasses.replace(frame, contacts=ContactsFrame(sources=("tuio:a",), ids=[1],
                                                                    positions=[[0.3, 0.2]], velocities=[[0, 0]]))
        scene.draw(touched)
        assert scene.nodes.contacts.visible
        assert np.allclose(scene.nodes.contacts.points[:, :2], [[0.3, 0.2]])
        scene.set_layer("contacts", False)
        assert not scene.nodes.contacts.visible
        scene.set_layer("contacts", True)
        scene.draw(frame)
        assert not scene.nodes.contacts.visible
        loop.close()
    finally:
        server.stop()


def test_html_export_prints_no_server_box_and_centres_the_arena(session, tmp_path, capfd):
    with open_recording(session) as rec:
        path, _ = export_html(rec, tmp_path / "r.html", fps=5.0)
    out = capfd.readouterr()
    assert "viser" not in out.out and "http://" not in out.out and "Websocket" not in out.out
    html = path.read_text()
    assert html  # the camera: the arena's centre in the middle of the page (no control panel to clear)
    assert cli(["export", str(session), "--html", str(tmp_path / "c.html")]) == 0
    out = capfd.readouterr().out
    assert "http://" not in out and "wrote" in out


def test_the_scene_centres_the_arena_without_a_panel():
    from swarmdeck.console.web.scene import SceneStyle

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        ArenaScene(server, (-1.6, 1.6, -1.0, 1.0), style=SceneStyle(panel_shift=0.0))
        assert np.allclose(server.initial_camera.look_at[:2], (0.0, 0.0))
    finally:
        server.stop()


def test_goto_draws_its_goals_live_and_in_playback(tmp_path):
    from swarmdeck.console.runtime.behaviours import cluster_goals, default_goals

    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        scene = ArenaScene(server)
        loop = ControlLoop(LoopConfig(n_robots=6, seed=1, behaviour="goto"))
        frames = [loop.tick()]
        scene.draw(frames[0])
        assert scene.nodes.goals.visible
        assert np.allclose(scene.nodes.goals.points[:, :2], default_goals(6, loop.config.bounds), atol=1e-6)
        loop.set_params(goal_centre=(0.8187636363636448, -0.3))
        frames.append(loop.tick())
        want = cluster_goals(6, (0.8187636363636448, -0.3), loop.config.bounds)
        scene.draw(frames[-1])
        assert np.allclose(scene.nodes.goals.points[:, :2], want, atol=1e-6)
        path = tmp_path / "g.mcap"
        with Recorder(path) as rec:
            for f in frames:
                rec.write_frame(f)
        with open_recording(path) as r:
            played = r.last_frame
        scene.draw(frames[0])
        scene.draw(played)
        assert np.allclose(scene.nodes.goals.points[:, :2], want, atol=1e-6)
        loop.set_behaviour("coverage")
        scene.draw(loop.tick())
        assert not scene.nodes.goals.visible  # no goals outside goto
        loop.close()
    finally:
        server.stop()
