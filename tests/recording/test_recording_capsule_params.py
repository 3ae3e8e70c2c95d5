"""`swarmdeck run --param` is part of what reproduces a run: the recording's capsule carries the values, and
`swarmdeck run run.zip` re-executes the script with them, bit for bit (before, the capsule dropped them and the
re-run used the script's defaults, so a run with --param never reproduced)."""
from __future__ import annotations

import json
import zipfile

from swarmdeck.console.cli import main as cli

SCRIPT = """import numpy as np
from swarmdeck.devices import params

p = params(speed=0.01)

def experiment(arena):
    while arena.time < arena.duration - 1e-9:
        arena.set_unicycle(np.full(arena.n, p.speed), np.full(arena.n, 0.3))
        arena.step()
"""


def test_a_run_with_param_values_reproduces_bit_for_bit_from_its_capsule(tmp_path, capsys) -> None:
    (tmp_path / "drive.py").write_text(SCRIPT)
    assert cli(["run", str(tmp_path / "drive.py"), "--robots", "2", "--duration", "0.5", "--seed", "3",
                "--param", "speed=0.08", "--record", str(tmp_path / "r.mcap"), "--no-foxglove-channels"]) == 0
    assert cli(["capsule", str(tmp_path / "r.mcap"), "-o", str(tmp_path / "run.zip")]) == 0
    with zipfile.ZipFile(tmp_path / "run.zip") as z:
        assert json.loads(z.read("manifest.json"))["run"]["params"] == {"speed": 0.08}
    capsys.readouterr()
    code = cli(["run", str(tmp_path / "run.zip"), "--json"])
    verdict = json.loads(capsys.readouterr().out)
    assert code == 0 and verdict["bit_identical"] and verdict["compared"] > 10, verdict
