"""A job's script parameters (the manifest's ``params``, `swarmdeck submit --param`): checked against what the
script declares with ``swarmdeck.devices.params`` before anything is stored (422 naming ``params``), then given to
every verification run and to the arena run, shown on the API and carried in the job's capsule."""
import json
import subprocess

import pytest
from portal_fixtures import CLI, wait_for_state

from swarmdeck.console.portal.errors import BadInput
from swarmdeck.console.portal.exports import JobExports
from swarmdeck.console.portal.runner import ArenaRunner, ArenaSettings
from swarmdeck.console.portal.submission import parse_params
from swarmdeck.console.portal.workers import VerificationWorkers
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.executors import SerialExecutor

# run with its defaults the script fails at once, so a job that verifies and runs to "done" got the values
SCRIPT = """import numpy as np
from swarmdeck.devices import params
p = params(gain=1.0, label="ring")

def experiment(arena):
    if p.gain == 1.0:
        raise RuntimeError("ran with the defaults")
    print(f"gain={p.gain} label={p.label}", flush=True)
    while True:
        arena.set_unicycle(np.full(arena.n, 0.01 * p.gain), np.zeros(arena.n))
        arena.step()
"""


@pytest.mark.parametrize("value,words", [
    ([1, 2], "params must be an object"),
    ({"not a name": 1}, "is not a parameter name"),
    ({"gain": float("inf")}, "gain must be finite"),
    ({"gain": [1]}, "gain must be a number, true/false or text"),
    ({"label": "x" * 201}, "printable text of at most 200"),
    ({f"p{k}": 1 for k in range(65)}, "at most 64 parameters"),
])
def test_malformed_params_are_refused_naming_the_key(value, words):
    with pytest.raises(BadInput) as got:
        parse_params(value)
    assert got.value.field == "params" and words in str(got.value), str(got.value)


def test_params_the_script_does_not_declare_or_of_another_kind_are_refused_before_anything_is_stored(portal):
    for params, words in (({"speed": 2}, "'speed' not declared by the script (it declares: gain, label)"),
                          ({"gain": "fast"}, "parameter gain is a float"),
                          ({"label": 3}, "parameter label is a str")):
        r = portal.submit("alice", SCRIPT, "g.py", robots=2, duration=1.0, params=params)
        assert r.status_code == 422 and r.json()["field"] == "params" and words in r.json()["error"], r.text
    with portal.client("alice") as c:
        assert c.get("/api/jobs").json() == []


@pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")
def test_verification_and_the_arena_run_get_the_values_and_the_capsule_keeps_them(portal, tmp_path):
    script = tmp_path / "g.py"
    script.write_text(SCRIPT)
    out = subprocess.run([*CLI, "submit", str(script), "--robots", "2", "--duration", "1", "--param", "gain=2",
                          "--param", "label=line", "--json", "--server", portal.url, "--token", portal.tokens["alice"]],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    job = json.loads(out.stdout)
    assert job["params"] == {"gain": 2, "label": "line"} and job["origin"] is None, job
    jid, svc = job["id"], portal.service
    workers = VerificationWorkers(svc, SerialExecutor(), poll_s=0.1).start()
    runner = ArenaRunner(svc, ArenaSettings(fleet=4, fast=True, seed=5), poll_s=0.05,
                         exports=JobExports(svc, video=False))
    svc.arena = runner
    runner.start()
    try:
        with portal.client("alice") as c:
            done = wait_for_state(c, jid, ("done", "failed", "rejected"), timeout=180)
            assert done["state"] == "done", done  # the defaults would have failed verification
            log = c.get(f"/api/jobs/{jid}/log").json()["text"]
            assert "gain=2.0 label=line" in log, log
    finally:
        runner.stop()
        workers.stop()
    from swarmdeck.console.portal.runner import _job_capsule

    capsule, _ = _job_capsule(svc, svc.store.get(jid), False)
    assert capsule.run["params"] == {"gain": 2, "label": "line"}
