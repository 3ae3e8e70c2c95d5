"""One time base for what a user sees and seeks to: session time, s since the session's first frame.

The loop's clock here starts at 1000 s (as ``time.monotonic`` does on a machine that has been up a
while); the recording is made from the first tick, as ``swarmdeck console`` makes it.
"""
from __future__ import annotations

import viser

from swarmdeck.console.cli.info import summarise
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.recording.recorder import Recorder
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.console.web.gui import ConsoleGui
from swarmdeck.console.web.player import Player
from swarmdeck.console.web.scene import ArenaScene

DT = 0.033


class OffsetClock:
    """The loop's clock: 1000 s plus one dt per tick (the loop reads it once per tick)."""

    def __init__(self) -> None:
        self.t = 1000.0 - DT

    def __call__(self) -> float:
        self.t += DT
        return self.t


def _session(tmp_path):
    loop = ControlLoop(LoopConfig(n_robots=5, seed=2, dt=DT), clock=OffsetClock())
    rec = Recorder(tmp_path / "run.mcap", {"robots": list(range(5))})
    loop.subscribe(rec.write_frame)
    frames = [loop.tick() for _ in range(10)]
    loop.pause()  # run time stops; session time goes on
    frames += [loop.tick() for _ in range(10)]
    loop.estop()
    frames += [loop.tick() for _ in range(10)]
    assert rec.close().state == "closed"
    return loop, frames, tmp_path / "run.mcap"


def test_info_event_times_are_seekable_in_the_player(tmp_path) -> None:
    _, frames, path = _session(tmp_path)
    stop_frame = next(f for f in frames if "EMERGENCY STOP" in f.events)
    line = next(e for e in summarise(str(path))["first_events"] if "EMERGENCY STOP" in e)
    t = float(line.split(" s ")[0])
    assert abs(t - (stop_frame.time - frames[0].time)) < 1e-3  # session time, not the loop's 1000 s clock
    with open_recording(path) as rec:
        assert t <= rec.duration
        player = Player(rec)
        shown = player.seek(t)
        assert shown.tick == stop_frame.tick and "EMERGENCY STOP" in shown.events
        ev = next(e for e in rec.events() if "EMERGENCY STOP" in e.text)
        assert ev.t == player.frame_time and ev.console_t == stop_frame.time


def test_the_live_panel_shows_session_time_and_labels_run_time(tmp_path) -> None:
    loop, frames, _ = _session(tmp_path)
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        gui = ConsoleGui(server, loop, ArenaScene(server, loop.config.bounds))
        for f in frames:
            gui.record(f)
        last = frames[-1]
        gui.update(last, force=True)
        session = last.time - frames[0].time
        assert loop.time_origin == frames[0].time
        assert f"t = {session:.1f} s" in gui.status.content
        assert f"run t = {last.run_time:.1f} s" in gui.status.content and session > last.run_time + 0.3
        x = gui.plots.dist.data[0]
        assert abs(x[0]) < 1e-9 and abs(x[-1] - session) < 1e-9
        # the alert list under the status line gives each alert its session time
        stop_t = next(f for f in frames if "EMERGENCY STOP" in f.events).time - frames[0].time
        assert f"{stop_t:.1f} s · EMERGENCY STOP" in gui.alerts.content
    finally:
        server.stop()
