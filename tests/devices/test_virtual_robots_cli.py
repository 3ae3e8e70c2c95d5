"""``swarmdeck console --virtual K``: K virtual robots beside the physical (here: simulated) ones, recorded as such."""
from __future__ import annotations

import pytest

from swarmdeck.console.cli import main
from swarmdeck.console.recording.reader import open_recording


def test_console_adds_virtual_robots_and_records_them(tmp_path, capsys) -> None:
    path = tmp_path / "mixed.mcap"
    rc = main(["console", "--port", "0", "--duration", "0.5", "--robots", "4", "--virtual", "3", "--no-inputs",
               "--seed", "2", "--record", str(path)])
    assert rc == 0
    assert "4 + 3 virtual robots" in capsys.readouterr().out
    with open_recording(path) as r:
        frames = [f for _, f in r.frames()]
    assert frames and all(f.is_virtual.tolist() == [False] * 4 + [True] * 3 for f in frames)
    assert all("virtual: 3 robots" in f.health["robots"] for f in frames)


@pytest.mark.parametrize("argv, message", [
    (["console", "--virtual", "0", "--no-inputs"], "--virtual must be"),
    (["console", "--virtual", "400", "--no-inputs", "--no-record"], "do not fit"),
])
def test_bad_virtual_counts_are_one_line_usage_errors(capsys, argv, message) -> None:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
