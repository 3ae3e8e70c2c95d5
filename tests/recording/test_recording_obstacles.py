"""Obstacles recorded and replayed: a console run and a `swarmdeck run --obstacles` run with a wall record the
obstacles once in the recording's config and in the Frames (keyframes, or when they change), the player reads
them back on every Frame, re-simulation reproduces the run, and bad obstacle files are refused naming the key."""
from __future__ import annotations

import textwrap

import numpy as np
import pytest

from swarmdeck.console.cli import main
from swarmdeck.console.recording.codec import decode_frame, encode_frame
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.recording.recorder import Recorder, RecorderConfig
from swarmdeck.console.recording.resimulate import resimulate_and_compare, session_metadata
from swarmdeck.console.runtime.config import ConfigFileError, load_settings
from swarmdeck.console.runtime.loop import ControlLoop
from swarmdeck.core.obstacles import Obstacles, point_segment_distance

WALL_TOML = """
[console]
robots = 5
seed = 3
behaviour = "rendezvous"

[arena]
obstacles = [[[-0.4, 0.0], [0.4, 0.0]], {polygon = [[1.0, 0.5], [1.3, 0.5], [1.3, 0.8]]}]
"""


def test_console_run_with_obstacles_records_and_replays(tmp_path) -> None:
    conf = tmp_path / "arena.toml"
    conf.write_text(WALL_TOML)
    cfg = load_settings(conf).loop
    assert cfg.obstacles is not None and cfg.obstacles.m == 4
    path = tmp_path / "session.mcap"
    rec = Recorder(path, session_metadata(cfg), RecorderConfig(chunk_frames=8))
    loop = ControlLoop(cfg)
    loop.subscribe(rec.write_frame)
    live = [loop.tick() for _ in range(40)]
    loop.close()
    assert rec.close().frames == 40
    assert all(f.obstacles == cfg.obstacles for f in live)
    with open_recording(path) as r:
        frames = [f for _, f in r.frames()]
        meta = r.config()
        res = resimulate_and_compare(r)
    assert res.ok, res.summary()
    assert meta["config"]["loop"]["obstacles"] == cfg.obstacles.to_list()
    assert len(frames) == 40 and all(f.obstacles == cfg.obstacles for f in frames)
    for f in frames:  # the barrier kept every robot's body off the segments
        d = point_segment_distance(f.poses[:, :2], cfg.obstacles.segments)
        assert d.min() > 0.055


def test_predicted_frames_carry_obstacles_only_when_they_change() -> None:
    n = 2
    obs = Obstacles([[[0.0, 0.0], [0.5, 0.0]]])

    def frame(tick: int, obstacles: Obstacles | None):
        from swarmdeck.console.runtime.frame import Frame
        return Frame(tick=tick, time=tick * 0.033, poses=np.zeros((n, 3)) + [[0.0, 0.5, 0.0]], ids=np.arange(n),
                     nominal=np.zeros((n, 2)), safe=np.zeros((n, 2)), v=np.zeros(n), w=np.zeros(n), obstacles=obstacles)

    a, b, c = frame(1, obs), frame(2, obs), frame(3, None)
    ka, kb, kc = encode_frame(a), encode_frame(b, a), encode_frame(c, b)
    assert b"obstacles" in ka and b"obstacles" not in kb and b'"obstacles":[]' in kc.replace(b" ", b"")
    da = decode_frame(ka)
    db = decode_frame(kb, da)
    dc = decode_frame(kc, db)
    assert da.obstacles == obs and db.obstacles == obs and dc.obstacles is None


SCRIPT = """
    import numpy as np

    def experiment(arena):
        goals = arena.poses().copy()
        goals[:, 1] = -goals[:, 1]
        while True:
            arena.set_goals(goals)
            arena.step()
"""


def test_swarmdeck_run_obstacles_file_records_them(tmp_path, capsys) -> None:
    script = tmp_path / "cross.py"
    script.write_text(textwrap.dedent(SCRIPT))
    conf = tmp_path / "walls.toml"
    conf.write_text("[arena]\nobstacles = [[[-1.2, 0.0], [1.2, 0.0]]]\n")
    path = tmp_path / "run.mcap"
    assert main(["run", str(script), "--robots", "6", "--duration", "2", "--seed", "5", "--obstacles", str(conf),
                 "--record", str(path), "--json"]) == 0
    out = capsys.readouterr().out
    assert '"steps_with_collision": 0' in out
    assert "steps_with_obstacle_contact" not in out  # none
    with open_recording(path) as r:
        frames = [f for _, f in r.frames()]
    assert frames and all(f.obstacles is not None and f.obstacles.m == 1 for f in frames)
    sides = np.sign(frames[0].poses[:, 1])
    assert np.all(np.sign(frames[-1].poses[:, 1]) == sides)  # nobody passed through the wall


@pytest.mark.parametrize("text, words", [
    ("[arena]\nobstacles = [[[0.0, 0.0], [0.0, 0.0]]]\n", r"\[arena\] obstacles: .*segment 0 has zero length"),
    ("[arena]\nobstacles = [[[0.0, 0.0], [3.0, 0.0]]]\n", r"\[arena\] obstacles: .*segment 0 .*outside the arena"),
    ("[arena]\nobstacles = [[[0.0, 0.0], [0.5, 0.0]], {circle = [0, 0]}]\n", r"\[arena\] obstacles: .*entry 1"),
    ("[arena]\nwalls = 3\n", r"unknown key\(s\) \['walls'\] in \[arena\]"),
    ("[arena]\nobstacles = \"none\"\n", r"\[arena\] obstacles: obstacles must be a list"),
])
def test_bad_obstacle_config_is_refused_naming_the_key(tmp_path, text: str, words: str) -> None:
    conf = tmp_path / "bad.toml"
    conf.write_text(text)
    with pytest.raises(ConfigFileError, match=words):
        load_settings(conf)


def test_swarmdeck_run_refuses_a_bad_obstacles_file(tmp_path, capsys) -> None:
    script = tmp_path / "s.py"
    script.write_text(textwrap.dedent(SCRIPT))
    conf = tmp_path / "bad.toml"
    conf.write_text("[arena]\nobstacles = [[[0.0, 0.0], [0.0, 0.0]]]\n")
    assert main(["run", str(script), "--robots", "2", "--duration", "0.1", "--obstacles", str(conf)]) == 2
    assert "[arena] obstacles: obstacles entry 0: segment 0 has zero length" in capsys.readouterr().err
