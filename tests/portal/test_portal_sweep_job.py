"""A sweep submitted to the portal as ONE job (issue 31): it runs in simulation on the verification executor (never
the arena queue), ends done with its table, summary and report on the API and the job page, its runs' CPU is
charged to the researcher's daily limit, and another researcher sees nothing of it (404)."""
import json
import subprocess

import pytest
from portal_fixtures import CLI, sign_in, wait_for_state

from swarmdeck.console.portal.workers import VerificationWorkers
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.executors import SerialExecutor

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")

SCRIPT = """
import numpy as np
from swarmdeck.devices import params, record_metrics
p = params(gain=1.0)

def experiment(arena):
    while True:
        arena.set_unicycle(np.full(arena.n, 0.02 * p.gain), np.zeros(arena.n))
        record_metrics(gain_seen=p.gain)
        arena.step()
"""


def test_a_sweep_is_one_job_run_in_simulation_with_its_report_on_the_api_and_the_page(portal, tmp_path):
    sweep = {"name": "gain sweep", "params": ["gain=0.5,1"], "robots": 2, "seeds": 1, "duration": 1.0}
    with portal.client("alice") as c:
        # the CLI's refusal, as 422 with its message, before anything is stored
        bad = c.post("/api/sweeps", files={"script": ("g.py", SCRIPT)},
                     data={"sweep": json.dumps({**sweep, "params": ["speed=1,2"]})})
        assert bad.status_code == 422 and "does not declare a parameter 'speed'" in bad.json()["error"], bad.text
    script = tmp_path / "gain.py"
    script.write_text(SCRIPT)
    out = subprocess.run([*CLI, "submit", str(script), "--sweep", "--param", "gain=0.5,1", "--seeds", "1",
                          "--robots", "2", "--duration", "1", "--json", "--server", portal.url,
                          "--token", portal.tokens["alice"]], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    job = json.loads(out.stdout)
    assert job["state"] == "awaiting verification" and job["sweep"]["params"] == ["gain=0.5,1"], job
    assert job["name"] == "gain" and job["sweep"]["seeds"] == 1
    jid = job["id"]
    workers = VerificationWorkers(portal.service, SerialExecutor(), poll_s=0.2).start()
    try:
        with portal.client("alice") as c:
            job = wait_for_state(c, jid, ("done", "failed", "rejected"), timeout=120)
    finally:
        workers.stop()
    assert job["state"] == "done", job
    assert job["started"] is None and job["verdict"] is None  # never on the arena, no arena verdict
    with portal.client("alice") as c:
        results = c.get(f"/api/jobs/{jid}/results").json()
        s = results["sweep"]
        assert s["runs"] == 2 and s["failed"] == 0, s
        assert [row["gain"] for row in s["summary"]] == ["0.5", "1.0"]
        assert [row["metric_gain_seen_mean"] for row in s["summary"]] == ["0.5", "1.0"], s["summary"]
        names = {f["name"] for f in c.get(f"/api/jobs/{jid}/files").json()}
        assert {"sweep-report.html", "results.csv", "results.parquet", "summary.csv"} <= names, names
        report = c.get(f"/api/jobs/{jid}/files/sweep-report.html")
        assert report.status_code == 200 and "Sweep of" in report.text
        assert "sandbox" in report.headers["content-security-policy"]
        plot = report.text.split('img src="')[1].split('"')[0]
        assert plot.startswith("plots/") and c.get(f"/api/jobs/{jid}/files/{plot}").content[:4] == b"\x89PNG"
        assert c.get("/api/me").json()["limits"]["verify_cpu_s_today"]["used"] > 0  # the runs count against the limit
    browser, _ = sign_in(portal, "alice")
    try:
        page = browser.get(f"/jobs/{jid}").text
        assert 'id="sweep-summary"' in page and f"/jobs/{jid}/files/sweep-report.html" in page
        assert browser.get(f"/jobs/{jid}/files/{plot}").status_code == 200
    finally:
        browser.close()
    with portal.client("bob") as c:  # another researcher's sweep: 404 as everywhere
        for path in ("", "/results", "/files", "/files/sweep-report.html", f"/files/{plot}"):
            assert c.get(f"/api/jobs/{jid}{path}").status_code == 404, path
