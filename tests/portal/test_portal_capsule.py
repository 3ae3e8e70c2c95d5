"""A portal job's results include its capsule (the API's files, the job page's downloads); `swarmdeck capsule JOB`
downloads it and `swarmdeck run capsule.zip` re-runs the script in the sandbox, bit for bit."""
import json
import zipfile

import pytest
from mqtt_broker import wait_until
from portal_fixtures import sign_in, wait_for_state

from swarmdeck.console.cli import main
from swarmdeck.console.portal.exports import JobExports
from swarmdeck.console.portal.runner import ArenaRunner, ArenaSettings
from swarmdeck.console.sandbox.confinement import probe

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")

STEER = ("import numpy as np\n"
         "def experiment(arena):\n"
         "    while True:\n"
         "        p = arena.poses()\n"
         "        arena.set_unicycle(np.full(arena.n, 0.05), 0.8 * np.sin(3.0 * p[:, 2] + p[:, 0]))\n"
         "        arena.step()\n")


def test_a_portal_job_reproduces_bit_for_bit_from_its_capsule(portal, tmp_path, capsys) -> None:
    svc = portal.service
    runner = ArenaRunner(svc, ArenaSettings(fleet=4, fast=True, seed=5), poll_s=0.05,
                         exports=JobExports(svc, video=False))
    svc.arena = runner
    jid = portal.submit("alice", STEER, "steer.py", robots=2, duration=0.5).json()["id"]
    with svc.db.transaction() as tx:
        for s in ("verifying", "awaiting approval", "in arena queue"):
            svc.db.transition(tx, jid, s, **({"verdict": "accepted"} if s == "awaiting approval" else {}))
    runner.start()
    try:
        with portal.client("alice") as c:
            wait_for_state(c, jid, ("done",))
            wait_until(lambda: c.get(f"/api/jobs/{jid}").json()["exports"] != "writing", timeout=240,
                       what="the job's exports")
            assert c.get(f"/api/jobs/{jid}").json()["exports"] == "ready"
            files = {f["name"]: f for f in c.get(f"/api/jobs/{jid}/files").json()}
            assert "capsule.zip" in files and "reproduces the run" in files["capsule.zip"]["what"]
        browser, _ = sign_in(portal, "alice")
        try:
            assert "files/capsule.zip" in browser.get(f"/jobs/{jid}").text  # a download on the job page
        finally:
            browser.close()
    finally:
        runner.stop()
    out = tmp_path / "job.zip"
    assert main(["capsule", str(jid), "-o", str(out), "--server", portal.url, "--token", portal.tokens["alice"]]) == 0
    with zipfile.ZipFile(out) as z:
        m = json.loads(z.read("manifest.json"))
        assert m["kind"] == "portal" and m["entry"] == "script.py" and m["run"]["sandbox"] is True
        assert z.read("files/script.py") == STEER.encode()
    capsys.readouterr()
    code = main(["run", str(out), "--json"])
    v = json.loads(capsys.readouterr().out)
    assert code == 0, json.dumps(v)
    assert v["bit_identical"] and v["compared"] == v["recorded_frames"] > 10, v
