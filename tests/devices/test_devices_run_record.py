"""`swarmdeck run --record PATH` writes an MCAP recording of the run, as the console does."""
import textwrap

import numpy as np

from swarmdeck.console.cli import main
from swarmdeck.console.recording.reader import open_recording

SCRIPT = """
    from swarmdeck.devices import Arena

    def experiment(arena):
        while True:
            p = arena.positions()
            arena.set_velocities(-(p - p.mean(axis=0)))
            arena.step()
"""


def test_run_record_writes_a_recording_the_player_reads(tmp_path, capsys):
    script = tmp_path / "rendezvous.py"
    script.write_text(textwrap.dedent(SCRIPT))
    path = tmp_path / "run.mcap"
    assert main(["run", str(script), "--robots", "4", "--duration", "1", "--seed", "2", "--record", str(path)]) == 0
    assert "recorded 31 frames" in capsys.readouterr().err
    with open_recording(path) as rec:
        frames = [frame for _, frame in rec.frames()]
        meta = rec.config()
    assert len(frames) == 31 and frames[0].tick == 0 and frames[-1].tick == 30  # 1 s / 0.033 s
    assert meta["config"]["loop"]["n_robots"] == 4 and meta["config"]["loop"]["behaviour"] == "script:rendezvous.py"
    assert frames[0].barrier.enabled
    spread = [np.ptp(f.poses[:, :2], axis=0).sum() for f in frames]
    assert spread[-1] < spread[0]  # the robots gathered
