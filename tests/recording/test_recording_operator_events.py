"""Operator actions are typed events: stamped with the tick they take effect in, recorded on /swarmdeck/operator
(``Recorder.follow``), and re-simulation replays them — bumps painted and dragged in the browser included —
while recordings from before the events still re-simulate from their frames."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.recording.recorder import Recorder, RecorderConfig
from swarmdeck.console.recording.resimulate import resimulate_and_compare, session_metadata
from swarmdeck.console.runtime import operator_events as ev
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.console.runtime.params import DensityParams

BEFORE = Path(__file__).resolve().parents[1] / "data" / "console_before_operator_events.mcap"


def _session(loop: ControlLoop, n_ticks: int = 64) -> list:
    """Every kind of operator action, between ticks on the virtual clock."""
    bump: list[int] = []
    actions = {
        3: lambda: bump.append(loop.add_bump((0.5, 0.3), 0.3, 2.0)),
        5: lambda: loop.move_bump(bump[0], (0.55, 0.32)),
        6: lambda: loop.move_bump(bump[0], (0.6, 0.34)),
        8: lambda: loop.set_params(kappa=2.0, law="lloyd"),
        10: lambda: loop.update_bump(bump[0], sigma=0.4),
        12: loop.pause, 14: lambda: loop.step(2), 18: loop.run,
        20: lambda: loop.set_safety(enabled=False),
        24: lambda: loop.set_safety(enabled=True, gamma=50.0),
        26: lambda: loop.set_density(moving=False, bump_sigma=0.2),
        28: lambda: loop.add_bump((-0.4, -0.2)),
        32: lambda: loop.remove_bump(bump[0]),
        36: loop.estop, 39: loop.release, 41: loop.run,
        44: lambda: loop.set_params(goal_centre=(0.2, -0.1)), 45: lambda: loop.set_behaviour("goto"),
        52: lambda: loop.set_behaviour("rendezvous"),
    }
    frames = []
    for k in range(n_ticks):
        if k in actions:
            actions[k]()
        frames.append(loop.tick())
    return frames


def test_every_action_is_recorded_and_replayed_bit_for_bit(tmp_path) -> None:
    path = tmp_path / "s.mcap"
    cfg = LoopConfig(n_robots=6, seed=4)
    rec = Recorder(path, session_metadata(cfg, None), RecorderConfig(foxglove=False))
    loop = ControlLoop(cfg)
    rec.follow(loop)
    live = _session(loop)
    loop.close()
    rec.close()
    assert sum(f.density.n_bumps for f in live) > 0
    with open_recording(path) as r:
        assert r.config()["config"]["operator_events"] == 1
        events = list(r.operator_events())
        kinds = {type(e.event).__name__ for e in events}
        assert kinds == set(ev.EVENT_TYPES)  # every kind of action was recorded
        assert [e.tick for e in events if isinstance(e.event, ev.EStop)] == [36]
        res = resimulate_and_compare(r)
    assert res.frames == len(live) and res.ok, res.summary()


def test_the_bumps_alone_were_lost_before_operator_events(tmp_path) -> None:
    """The same session recorded without the events (as before them): the frames replay run state and
    parameters, but not the bumps — the first difference is where the first bump appeared."""
    path = tmp_path / "old.mcap"
    cfg = LoopConfig(n_robots=6, seed=4)
    rec = Recorder(path, session_metadata(cfg, None), RecorderConfig(foxglove=False))
    loop = ControlLoop(cfg)
    loop.subscribe(rec.write_frame)
    _session(loop, 20)
    loop.close()
    rec.close()
    with open_recording(path) as r:
        assert list(r.operator_events()) == []
        res = resimulate_and_compare(r)
    assert res.first_difference.tick == 3 and "density" in res.differing_keys


def test_a_recording_from_before_operator_events_still_resimulates() -> None:
    """tests/data/console_before_operator_events.mcap: recorded at commit 4bf2a57 (params, pause/step,
    barrier gains, circling bump off, e-stop and release, a behaviour switch), replayed from its frames."""
    with open_recording(BEFORE) as r:
        assert "operator_events" not in r.config()["config"]
        res = resimulate_and_compare(r)
    assert res.frames == 60 and res.ok, res.summary()


def test_events_are_stamped_with_the_tick_that_first_runs_with_them() -> None:
    loop = ControlLoop(LoopConfig(n_robots=3, seed=1), guard=None)
    got: list[ev.Stamped] = []
    loop.subscribe_operator(got.extend)
    loop.tick()
    loop.pause()
    loop.set_safety(gamma=30.0)
    assert got == []  # queued: nothing has taken effect yet
    f = loop.tick()
    assert [(s.tick, type(s.event)) for s in got] == [(1, ev.Pause), (1, ev.SetSafety)]
    assert got[1].event.changes == (("gamma", 30.0),) and got[1].time == f.time and f.params["gamma"] == 30.0
    loop.close()


def test_a_bump_added_during_a_tick_lands_whole_at_the_next_one() -> None:
    """Another thread's edit in the middle of a tick (here: from inside the behaviour) does not change
    the density that tick's behaviour sees; the next tick has it (and its event says so)."""
    loop = ControlLoop(LoopConfig(n_robots=3, seed=1, density=DensityParams(moving=False)))
    seen: list[int] = []

    class Painter:
        name = "painter"

        def __call__(self, tick):
            if not seen:
                loop.add_bump((0.1, 0.1))
            seen.append(tick.density.at(tick.t).n_bumps)
            return np.zeros((len(tick.poses), 2)), None

    stamps: list[ev.Stamped] = []
    loop.subscribe_operator(stamps.extend)
    loop.use_behaviour(Painter())
    first = loop.tick()
    second = loop.tick()
    assert seen == [0, 1] and first.density.n_bumps == 0 and second.density.n_bumps == 1
    assert [s.tick for s in stamps if isinstance(s.event, ev.AddBump)] == [1]
    loop.close()


def test_wire_form_round_trips_and_names_what_is_wrong() -> None:
    samples = [ev.Run(), ev.Pause(), ev.Step(3), ev.EStop(), ev.Release(), ev.SwitchBehaviour("goto"),
               ev.SetParams((("goal_centre", (0.5, -0.25)), ("kappa", 2.0))), ev.SetSafety((("enabled", False),)),
               ev.SetDensity((("moving", False),)), ev.AddBump(0, 0.1, 0.2, 0.3, 1.0, 0.5),
               ev.MoveBump(0, 0.2, 0.2, 0.6), ev.UpdateBump(0, weight=2.0), ev.RemoveBump(0, 0.9)]
    for e in samples:
        s = ev.Stamped(7, 1.25, e)
        back = ev.event_from_dict(json.loads(json.dumps(ev.event_to_dict(s))))
        assert back.tick == 7 and back.time == 1.25 and type(back.event) is type(e)
    sp = ev.event_from_dict(ev.event_to_dict(ev.Stamped(0, 0.0, samples[6])))
    assert sp.event.as_kwargs() == {"goal_centre": (0.5, -0.25), "kappa": 2.0}
    with pytest.raises(ValueError, match="Teleport"):
        ev.event_from_dict({"tick": 0, "time": 0.0, "type": "Teleport"})
    with pytest.raises(ValueError, match="tick"):
        ev.event_from_dict({"type": "Run"})


def test_an_action_that_cannot_be_replayed_is_noted(tmp_path) -> None:
    script = tmp_path / "b.py"
    script.write_text("import numpy as np\ndef behaviour(poses, t):\n    return np.zeros((len(poses), 2))\n")
    path = tmp_path / "s.mcap"
    cfg = LoopConfig(n_robots=3, seed=2)
    rec = Recorder(path, session_metadata(cfg, None), RecorderConfig(foxglove=False))
    loop = ControlLoop(cfg)
    rec.follow(loop)
    loop.tick()
    loop.set_behaviour(f"script:{script}")
    loop.tick()
    loop.close()
    rec.close()
    script.unlink()
    with open_recording(path) as r:
        res = resimulate_and_compare(r)
    assert not res.ok and any("SwitchBehaviour not replayed" in n for n in res.notes), res.summary()


def test_swarmdeck_info_says_whether_the_actions_were_recorded(tmp_path, capsys) -> None:
    from swarmdeck.console.cli import main

    path = tmp_path / "s.mcap"
    cfg = LoopConfig(n_robots=3, seed=2)
    rec = Recorder(path, session_metadata(cfg, None), RecorderConfig(foxglove=False))
    loop = ControlLoop(cfg)
    rec.follow(loop)
    loop.pause()
    loop.tick()
    loop.step(1)
    loop.tick()
    loop.close()
    rec.close()
    assert main(["info", str(path), "--resimulate"]) == 0
    out = capsys.readouterr().out
    assert "2 recorded actions (replayed by --resimulate)" in out and "2 identical" in out
    assert main(["info", str(BEFORE)]) == 0
    assert "actions not recorded" in capsys.readouterr().out
