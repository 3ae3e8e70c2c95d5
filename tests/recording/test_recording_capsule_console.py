"""A console session recorded by the console's recorder carries its capsule; its run.zip re-simulates bit for bit,
operator actions included."""
from __future__ import annotations

import json
import zipfile

from swarmdeck.console.cli import main as cli
from swarmdeck.console.cli.console import _recorder
from swarmdeck.console.recording.capsule_zip import read_recorded_capsule
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig


def test_a_console_session_with_operator_actions_reproduces_from_its_capsule(tmp_path, capsys) -> None:
    path = tmp_path / "session.mcap"
    cfg = LoopConfig(n_robots=4, seed=11)
    rec = _recorder(str(path), cfg, None, "simulation", foxglove_channels=False)
    loop = ControlLoop(cfg)
    rec.follow(loop)
    actions = {2: lambda: loop.set_params(kappa=2.0), 4: loop.pause, 5: lambda: loop.step(1), 7: loop.run,
               9: lambda: loop.add_bump((0.3, 0.2), 0.3, 2.0), 11: loop.estop, 13: loop.release, 14: loop.run,
               16: lambda: loop.set_behaviour("rendezvous")}
    for k in range(20):
        if k in actions:
            actions[k]()
        loop.tick()
    loop.close()
    assert rec.close().ok
    got = read_recorded_capsule(path)
    assert got.manifest is not None and got.manifest.kind == "console" and got.files == {}
    assert got.manifest.run["config"]["loop"]["seed"] == 11
    assert cli(["capsule", str(path), "-o", str(tmp_path / "session.zip")]) == 0
    with zipfile.ZipFile(tmp_path / "session.zip") as z:
        assert sorted(z.namelist()) == ["manifest.json", "recording.mcap"]
    capsys.readouterr()
    assert cli(["run", str(tmp_path / "session.zip"), "--json"]) == 0
    v = json.loads(capsys.readouterr().out)
    assert v["bit_identical"] and v["compared"] == v["recorded_frames"] == 20, v
