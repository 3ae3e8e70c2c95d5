"""Re-simulation runs the loop with the guard the recorded session ran with: a session whose barrier was switched
off replays bit for bit whether the guard watched it (recorded in ``config.guard``) or the recording predates the
guard (no ``guard`` key: that loop ran without one)."""
from __future__ import annotations

from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.recording.recorder import Recorder
from swarmdeck.console.recording.resimulate import resimulate_and_compare, session_metadata
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.safety.guard import GuardConfig


def record_barrier_off(path, guard, *, old_metadata=False, n_ticks=130):
    """Rendezvous with the barrier switched off at tick 3: the robots converge until the guard (if any) trips."""
    cfg = LoopConfig(n_robots=6, seed=5, behaviour="rendezvous")
    meta = session_metadata(cfg, None, guard=guard)
    if old_metadata:
        del meta["config"]["guard"]  # as written before the guard existed
    rec = Recorder(path, meta)
    loop = ControlLoop(cfg, guard=guard)
    loop.subscribe(rec.write_frame)
    loop.run()
    frames = []
    for k in range(n_ticks):
        if k == 3:
            loop.set_safety(enabled=False)
        frames.append(loop.tick())
    loop.close()
    rec.close()
    return loop, frames


def test_a_guarded_session_replays_bit_for_bit(tmp_path):
    path = tmp_path / "guarded.mcap"
    loop, frames = record_barrier_off(path, GuardConfig())
    assert loop.revocations, "the robots must converge far enough for the guard to switch the barrier back on"
    with open_recording(path) as r:
        assert r.config()["config"]["guard"] == {"guard_distance": 0.15, "max_intervention": 0.1}
        res = resimulate_and_compare(r)
    assert res.frames == len(frames) and res.ok, res.summary()


def test_a_recording_from_before_the_guard_replays_without_it(tmp_path):
    path = tmp_path / "old.mcap"
    loop, frames = record_barrier_off(path, None, old_metadata=True)
    assert not loop.revocations
    with open_recording(path) as r:
        assert "guard" not in r.config()["config"]
        res = resimulate_and_compare(r)
    assert res.frames == len(frames) and res.ok, res.summary()
