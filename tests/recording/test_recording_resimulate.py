"""Re-simulation: a recording's datagrams through the real TUIO parser into a fresh loop reproduce every frame."""
from __future__ import annotations

import pytest

from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.recording.recorder import Recorder
from swarmdeck.console.recording.resimulate import (
    compare_frames,
    loop_config_from_dict,
    loop_config_to_dict,
    resimulate_and_compare,
    session_metadata,
)
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.inputs import InputConfig, InputHub, InputSource
from swarmdeck.inputs.oscbuild import cursor_sets, tuio_bundle

INPUTS = {"listeners": [{"name": "table", "timeout": 0.3}]}


def record_session(path, n_ticks=70, bump_at=None):
    """A console run on the virtual clock: a TUIO finger touches the table for a while; the operator
    pauses, steps, changes κ, hits the e-stop and releases it. Returns the live frames."""
    cfg = LoopConfig(n_robots=6, seed=11)
    icfg = InputConfig.from_dict(INPUTS)
    rec = Recorder(path, session_metadata(cfg, INPUTS))
    src = InputSource(icfg.listeners[0], on_datagram=rec.datagram_hook("table"))
    loop = ControlLoop(cfg, inputs=InputHub([src], config=icfg))
    loop.subscribe(rec.write_frame)
    frames = []
    actions = {15: loop.pause, 18: lambda: loop.step(2), 22: lambda: (loop.run(), loop.set_params(kappa=2.5)),
               40: loop.estop, 44: loop.release, 47: loop.run}
    for k in range(n_ticks):
        if k in actions:
            actions[k]()
        if k == bump_at:
            loop.add_bump((0.5, 0.3))  # a browser action: not in the datagrams, not in the frame params
        frames.append(loop.tick())
        if 5 <= k < 55:  # the finger, arriving between ticks on the loop's clock
            x = 0.2 + 0.01 * k
            src.feed(tuio_bundle("2Dcur", [7], cursor_sets([(7, x, 0.4)]), fseq=k), ("10.0.0.5", 3333),
                     k * cfg.dt + 0.011)
    loop.close()
    assert rec.close().frames == n_ticks
    return frames


def test_resimulation_reproduces_every_frame(tmp_path):
    path = tmp_path / "session.mcap"
    live = record_session(path)
    assert sum(len(f.contacts) > 0 for f in live) > 30, "the finger must reach the loop"
    assert {f.run_state for f in live} == {"running", "paused", "estop"}
    with open_recording(path) as r:
        res = resimulate_and_compare(r)
    assert res.datagrams == 50 and res.frames == len(live)
    assert res.ok and res.first_difference is None, res.summary()


def test_an_unrecorded_action_is_reported_where_it_happened(tmp_path):
    path = tmp_path / "bump.mcap"
    record_session(path, n_ticks=40, bump_at=25)
    with open_recording(path) as r:
        res = resimulate_and_compare(r)
    assert not res.ok
    assert res.first_difference.tick == 25 and res.first_difference.key.startswith("density")
    assert res.identical >= 25 and "density bumps" in res.summary()


def test_compare_frames_sees_a_changed_pose(tmp_path):
    import dataclasses

    from recording_synth import simulated_frames

    f = next(simulated_frames(n_robots=3, n_ticks=1, coverage=False))
    poses = f.poses.copy()
    poses[1, 0] += 1e-12
    assert compare_frames(f, f) == []
    [(key, mag)] = compare_frames(f, dataclasses.replace(f, poses=poses))
    assert key == "poses" and mag == pytest.approx(1e-12, rel=1e-3)


def test_loop_config_round_trips():
    from swarmdeck.console.runtime.behaviours import BehaviourParams

    cfg = LoopConfig(n_robots=9, seed=3, behaviour="formation",
                     behaviour_params=BehaviourParams(kappa=2.0, goals=((0.1, 0.2),) * 9))
    assert loop_config_from_dict(loop_config_to_dict(cfg)) == cfg
    with pytest.raises(ValueError, match="LoopConfig"):
        loop_config_from_dict({"n_robots": 3, "warp_drive": True})
