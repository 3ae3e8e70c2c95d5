"""`swarmdeck server --arena NAME=SPEC` (repeatable): one portal, several arenas — a bad SPEC is a one-line usage
error; a real server process with a simulated arena and a remote one lists both, verifies a job and runs it on
the arena it asked for."""
import json

import httpx
import pytest
from portal_fixtures import SPIN, add_user, start_server, wait_for_state

from swarmdeck.console.cli import main
from swarmdeck.console.sandbox.confinement import probe


@pytest.mark.parametrize("argv,words", [
    (["--arena", "floor"], "write NAME=SPEC"),
    (["--arena", "floor=sim", "--arena", "floor=remote"], "two arenas are named 'floor'"),
    (["--arena", "floor=sim,robots=80"], "at most"),
    (["--arena", "floor=sim", "--robots", "4"], "leave out --robots"),
    (["--arena", "x=remote,kind=wooden"], "kind must be physical or simulated"),
    (["--smtp", "mail:99999"], "--smtp"),
])
def test_bad_arenas_exit_2_in_one_line(tmp_path, capsys, argv, words):
    assert main(["server", "--data", str(tmp_path / "lab"), "--port", "0", *argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and words in err, err


@pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")
def test_a_server_with_two_arenas_runs_a_job_on_the_one_it_asked_for(tmp_path):
    data = tmp_path / "lab"
    token = add_user(data, "alice", "researcher")
    server = start_server(data, "--arena", "floor=sim,robots=4,fast", "--arena", "annex=remote,robots=2,kind=physical",
                          "--workers", "1", "--verify-runs", "1")
    try:
        assert "arenas floor: 4 simulated robots" in "".join(server.output)
        with httpx.Client(base_url=server.url, headers={"Authorization": f"Bearer {token}"}, timeout=60) as c:
            arenas = {a["name"]: a for a in c.get("/api/arenas").json()}
            assert arenas["floor"]["connected"] and not arenas["annex"]["connected"]
            assert arenas["annex"]["kind"] == "physical" and arenas["annex"]["remote"]
            manifest = {"name": "spin", "robots": 2, "duration": 1.0, "arena": "floor"}
            job = c.post("/api/jobs", files={"script": ("spin.py", SPIN)}, data={"manifest": json.dumps(manifest)})
            assert job.status_code == 201, job.text
            too_big = c.post("/api/jobs", files={"script": ("spin.py", SPIN)},
                             data={"manifest": json.dumps({**manifest, "robots": 3, "arena": "annex"})})
            assert too_big.status_code == 422 and "has 2 robots" in too_big.json()["error"]
            done = wait_for_state(c, job.json()["id"], ("done", "failed", "rejected"), timeout=240)
            assert done["state"] == "done" and done["placed"] == "floor", done
    finally:
        server.stop()
