"""The Foxglove channels of a recording can be switched off (and back on) from the CLI and the config file:
`--no-foxglove-channels` / `--foxglove-channels`, `[console] foxglove_channels = false`."""
from __future__ import annotations

import pytest
from mcap.reader import make_reader

from swarmdeck.console.cli import main as cli
from swarmdeck.console.recording.foxglove import TOPICS
from swarmdeck.console.recording.schemas import CHANNELS
from swarmdeck.console.runtime.config import ConfigFileError, load_settings


def _topics(path) -> set[str]:
    with open(path, "rb") as fh:
        summary = make_reader(fh).get_summary()
    return {c.topic for c in summary.channels.values()}


def _run(tmp_path, *extra: str) -> set[str]:
    out = tmp_path / "s.mcap"
    code = cli(["console", "--port", "0", "--no-inputs", "--robots", "3", "--duration", "0.5",
                "--record", str(out), *extra])
    assert code == 0
    return _topics(out)


@pytest.mark.parametrize("file_says, flag, channels", [
    (None, [], True),
    (None, ["--no-foxglove-channels"], False),
    ("false", [], False),
    ("false", ["--foxglove-channels"], True),  # the command line wins over the file
    ("true", ["--no-foxglove-channels"], False),
])
def test_foxglove_channels_follow_the_flag_and_the_file(tmp_path, file_says, flag, channels):
    args = list(flag)
    if file_says is not None:
        cfg = tmp_path / "c.toml"
        cfg.write_text(f"[console]\nfoxglove_channels = {file_says}\n")
        args += ["--config", str(cfg)]
    topics = _run(tmp_path, *args)
    assert set(CHANNELS) - {"/swarmdeck/datagram"} <= topics  # swarmdeck's own channels always
    if channels:
        assert {"/foxglove/robots", "/foxglove/robot_points", "/foxglove/tf", "/swarmdeck/metrics"} <= topics
    else:
        assert not set(TOPICS) & topics


def test_a_bad_foxglove_channels_value_names_the_key(tmp_path):
    p = tmp_path / "c.toml"
    p.write_text('[console]\nfoxglove_channels = "no"\n')
    with pytest.raises(ConfigFileError, match=r"\[console\] foxglove_channels must be true or false"):
        load_settings(p)


def _written(path) -> set[str]:
    """The topics that have messages (a channel may be declared and never written)."""
    with open(path, "rb") as fh:
        return {c.topic for _, c, _ in make_reader(fh).iter_messages()}


def test_foxglove_entities_records_one_entity_per_robot_instead_of_the_packed_default(tmp_path):
    _run(tmp_path)
    packed = _written(tmp_path / "s.mcap")
    assert "/foxglove/robot_points" in packed and "/foxglove/poses" not in packed
    _run(tmp_path, "--foxglove-entities")
    entities = _written(tmp_path / "s.mcap")
    assert "/foxglove/poses" in entities and "/foxglove/robot_points" not in entities
