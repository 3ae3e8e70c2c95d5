"""The panel's status line and event list: "ticks/s" counts ticks over the last seconds (virtual clock);
repeated event lines of a failing script collapse ("× N"); the emergency stop is the panel's first widget,
above anything that grows; after its release the status line says the robots stay stopped until Run;
event lines show parameter values rounded."""
from __future__ import annotations

import itertools

import pytest
import viser

from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.console.web.events import EventLog
from swarmdeck.console.web.gui import ConsoleGui, TickRate
from swarmdeck.console.web.scene import ArenaScene


@pytest.fixture(scope="module")
def server():
    s = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield s
    s.stop()


def _console(server, clock=None, **config):
    server.gui.reset()
    server.scene.reset()
    loop = ControlLoop(LoopConfig(n_robots=4, seed=1, **config), clock=clock)
    return loop, ConsoleGui(server, loop, ArenaScene(server, loop.config.bounds))


def test_ticks_per_second_counts_ticks_over_a_window_of_the_loop_clock(server):
    # a 20 Hz loop whose ticks come unevenly: 10 ms, 90 ms, 10 ms, … (mean 50 ms)
    steps = itertools.cycle([0.01, 0.09])
    now = [100.0]

    def clock():
        t = now[0]
        now[0] += next(steps)
        return t

    loop, gui = _console(server, clock)
    for _ in range(200):
        frame = loop.tick()
        gui.record(frame)
    assert gui.rate.rate == pytest.approx(20.0, rel=0.03)
    assert f"{gui.rate.rate:.1f} ticks/s" in gui.status_line(frame)  # an average of 1/Δt said ≈ 55


def test_frames_the_viewer_skipped_still_count():
    rate = TickRate(window=2.0)
    for k in range(0, 300, 3):  # the viewer sees every third frame of a 30 Hz loop
        rate.add(k / 30.0, k)
    assert rate.rate == pytest.approx(30.0)


def test_a_failing_scripts_events_collapse_into_one_line(server, tmp_path):
    script = tmp_path / "bad.py"
    script.write_text("def behaviour(poses, t):\n    raise ValueError(f'boom at t={t:.3f}')\n")
    loop, gui = _console(server, behaviour=f"script:{script}", script_budget=0.5)
    for _ in range(120):
        gui.record(loop.tick())
    text = gui.alert_text(loop.latest)
    listed = [line for line in text.splitlines() if " s · " in line]
    assert len(listed) == 1 and listed[0].endswith("× 120") and "ValueError: boom at t=" in listed[0], text


def test_event_log_keeps_distinct_events_and_counts_repeats():
    log = EventLog(3)
    for k in range(5):
        log.add(k, f"retry {k}")
    log.add(6.0, "EMERGENCY STOP")
    log.add(7.0, "EMERGENCY STOP")
    assert log.lines() == ["4.0 s · retry 4 × 5", "7.0 s · EMERGENCY STOP × 2"]


def test_the_emergency_stop_is_the_first_widget_and_release_says_paused(server):
    loop, gui = _console(server)
    orders = {name: getattr(gui, name).order for name in ("estop_button", "release_button", "status", "alerts",
                                                                 "run_button")}
    assert orders["estop_button"] == min(orders.values())
    assert orders["estop_button"] < orders["status"] < orders["alerts"]
    assert "paused" in gui.release_button.label.lower() and "run" in gui.release_button.label.lower()
    gui.estop_button.value = True
    assert loop.tick().run_state == "estop"
    gui.release_button.value = True
    frame = loop.tick()
    assert frame.run_state == "paused"
    assert "press Run to resume" in gui.status_line(frame).splitlines()[0]


def test_event_lines_show_parameter_values_rounded(server):
    loop, _ = _console(server)
    loop.set_params(goal_centre=(0.8187636363636448, -0.41234567), gain=1.2345678)
    events = loop.tick().events
    assert "parameters: goal_centre=(0.82, -0.41), gain=1.23" in events, events
