"""`swarmdeck verify --manifest M` verifies what the portal will run: the manifest's script parameter values
(``params``) reach every run, as the portal's own verification gives them (before, they were ignored)."""
import json

import pytest

from swarmdeck.console.cli import main
from swarmdeck.console.sandbox.confinement import probe

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")

# with its defaults the script fails at once: only runs that got the manifest's values are accepted
SCRIPT = """import numpy as np
from swarmdeck.devices import params
p = params(gain=1.0)

def experiment(arena):
    if p.gain == 1.0:
        raise RuntimeError("ran with the defaults")
    while True:
        arena.set_unicycle(np.full(arena.n, 0.01 * p.gain), np.zeros(arena.n))
        arena.step()
"""


def test_the_manifests_params_reach_every_verification_run(tmp_path, capsys):
    script = tmp_path / "gain.py"
    script.write_text(SCRIPT)
    manifest = tmp_path / "manifest.json"
    manifest.write_text(json.dumps({"name": "gain", "robots": 2, "duration": 0.5, "params": {"gain": 2.0}}))
    assert main(["verify", str(script), "--manifest", str(manifest), "--runs", "1", "--paced-runs", "0",
                 "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["verdict"].startswith("accepted")
    manifest.write_text(json.dumps({"name": "gain", "robots": 2, "duration": 0.5}))
    main(["verify", str(script), "--manifest", str(manifest), "--runs", "1", "--paced-runs", "0", "--json"])
    assert json.loads(capsys.readouterr().out)["verdict"] == "rejected"
