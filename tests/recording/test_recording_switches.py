"""The recording's switches beyond the console's flag: `swarmdeck run --record PATH --no-foxglove-channels`,
and the config file's `[recording]` table (foxglove_channels, chunk_frames, robot_rate) with errors that
name the key."""
from __future__ import annotations

import textwrap

import pytest
from mcap.reader import make_reader

from swarmdeck.console.cli import main as cli
from swarmdeck.console.recording.foxglove import TOPICS
from swarmdeck.console.runtime.config import ConfigFileError, load_settings

SCRIPT = """
    from swarmdeck.devices import Arena

    def experiment(arena):
        while True:
            arena.set_velocities(0 * arena.positions())
            arena.step()
"""


def _topics(path) -> set[str]:
    with open(path, "rb") as fh:
        return {c.topic for c in make_reader(fh).get_summary().channels.values()}


@pytest.mark.parametrize("flag, channels", [([], True), (["--no-foxglove-channels"], False)])
def test_run_record_switches_the_foxglove_channels(tmp_path, flag, channels):
    script = tmp_path / "still.py"
    script.write_text(textwrap.dedent(SCRIPT))
    path = tmp_path / "run.mcap"
    assert cli(["run", str(script), "--robots", "3", "--duration", "0.3", "--record", str(path), *flag]) == 0
    topics = _topics(path)
    assert "/swarmdeck/frame" in topics
    assert bool(set(TOPICS) & topics) is channels


def test_the_recording_table_is_read(tmp_path):
    p = tmp_path / "c.toml"
    p.write_text("[recording]\nfoxglove_channels = false\nchunk_frames = 30\nrobot_rate = 500\n")
    s = load_settings(p)
    assert (s.foxglove_channels, s.chunk_frames, s.robot_rate) == (False, 30, 500.0)
    p.write_text("[console]\nrobots = 3\n")
    s = load_settings(p)
    assert (s.foxglove_channels, s.chunk_frames, s.robot_rate) == (True, 20, 1000.0)
    assert (s.packed, s.lines_period) == (True, 1.0)


def test_the_console_records_with_the_recording_table(tmp_path):
    cfg = tmp_path / "c.toml"
    cfg.write_text("[recording]\nfoxglove_channels = false\n")
    out = tmp_path / "s.mcap"
    assert cli(["console", "--port", "0", "--no-inputs", "--robots", "3", "--duration", "0.3",
                "--record", str(out), "--config", str(cfg)]) == 0
    assert not set(TOPICS) & _topics(out)


@pytest.mark.parametrize("text, match", [
    ("[recording]\nchunk_frames = 0\n", r"\[recording\] chunk_frames must be an integer >= 1"),
    ("[recording]\nchunk_frames = 2.5\n", r"\[recording\] chunk_frames"),
    ("[recording]\nrobot_rate = -1\n", r"\[recording\] robot_rate must be a number >= 0"),
    ("[recording]\nfoxglove_channels = 1\n", r"\[recording\] foxglove_channels must be true or false"),
    ("[recording]\nkeyframes = 3\n", r"keyframes"),
    ("[recording]\nfoxglove_channels = true\n[console]\nfoxglove_channels = true\n", r"give it once"),
])
def test_a_bad_recording_key_is_named(tmp_path, text, match):
    p = tmp_path / "c.toml"
    p.write_text(text)
    with pytest.raises(ConfigFileError, match=match):
        load_settings(p)
