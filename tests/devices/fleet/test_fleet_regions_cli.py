"""``swarmdeck regions``: check a layout (capacity), run unmodified scripts at once in its regions; bad input is one
line naming what is wrong."""
from __future__ import annotations

import json

import pytest

from swarmdeck.console.cli import main

LAYOUT = """
[regions.west]
bounds = [-1.6, 0.0, -1.0, 1.0]
chargers = ["left", "bottom", "top"]
[regions.east]
bounds = [0.0, 1.6, -1.0, 1.0]
chargers = ["right", "bottom", "top"]
"""

SCRIPT = """
import numpy as np
from swarmdeck.devices import Arena

arena = Arena()
while True:
    arena.set_velocities(np.tile([0.2, 0.0], (arena.n, 1)))
    arena.step()
"""


def test_check_prints_what_each_region_holds(tmp_path, capsys):
    (tmp_path / "floor.toml").write_text(LAYOUT)
    assert main(["regions", str(tmp_path / "floor.toml"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert [r["name"] for r in out["regions"]] == ["west", "east"] and out["capacity"] == {"west": 25, "east": 25}


def test_two_scripts_at_once_stay_in_their_regions(tmp_path, capsys):
    (tmp_path / "floor.toml").write_text(LAYOUT)
    (tmp_path / "east.py").write_text(SCRIPT)
    (tmp_path / "west.py").write_text(SCRIPT)
    code = main(["regions", str(tmp_path / "floor.toml"), "--run", f"west={tmp_path / 'west.py'}",
                 "--run", f"east={tmp_path / 'east.py'}", "--robots", "3", "--duration", "4", "--seed", "1", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0, out
    assert out["floor"]["outside"] == 0 and out["contacts"] == 0
    assert sorted(out["jobs"]) == ["east", "west"] and all(j["error"] is None for j in out["jobs"].values())


@pytest.mark.parametrize(("argv", "message"), [
    (["regions", "nope.toml"], "cannot read config file nope.toml"),
    (["regions", "9x1"], "region r0c0: the approach area"),
    (["regions", "2x1", "--run", "north=x.py"], "REGION one of r0c0, r0c1"),
    (["regions", "2x1", "--run", "r0c0=missing.py"], "no file missing.py"),
])
def test_bad_input_is_one_line(capsys, argv, message):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err
