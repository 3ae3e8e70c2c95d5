"""The lab's script environment on the portal and the command line: ``swarmdeck server --script-env`` verifies
and runs scripts with it, ``GET /api/env``, the Libraries page and ``swarmdeck env --server`` list it, and
``swarmdeck verify --script-env`` rejects a script importing outside it, naming the package."""
import json
import subprocess

import httpx
import pytest
from portal_fixtures import CLI, CSRF, add_user, start_server, wait_for_state
from script_env_fixtures import USES_THE_ENV

from swarmdeck.console.sandbox.import_policy import refusal


def cli(*args, timeout=120):
    return subprocess.run([*CLI, *args], capture_output=True, text=True, timeout=timeout)


@pytest.fixture
def server(tmp_path, env):
    data = tmp_path / "data"
    srv = start_server(data, "--script-env", str(env), "--verify-runs", "1", "--fast", "--robots", "2")
    try:
        yield srv, add_user(data, "alice", "researcher")
    finally:
        srv.stop()


def test_the_portal_lists_and_enforces_its_script_environment(server):
    srv, token = server
    with httpx.Client(base_url=srv.url, headers={"Authorization": f"Bearer {token}"}, timeout=30) as c:
        info = c.get("/api/env").json()
        assert {"name": "labtools", "version": "1.2"} in info["packages"]
        assert [p["name"] for p in info["provided"]] == ["numpy"]
        assert "ask the lab" in info["request"]
        ok = c.post("/api/jobs", files={"script": ("ok.py", USES_THE_ENV)},
                    data={"manifest": json.dumps({"name": "ok", "robots": 2, "duration": 1.0})}).json()
        bad = c.post("/api/jobs", files={"script": ("bad.py", "import msgspec\n" + USES_THE_ENV)},
                     data={"manifest": json.dumps({"name": "bad", "robots": 2, "duration": 1.0})}).json()
        assert wait_for_state(c, ok["id"], ("done",), timeout=240)["verdict"] != "rejected"
        rejected = wait_for_state(c, bad["id"], ("rejected",), timeout=240)
        assert refusal("msgspec") in rejected["reason"]
    assert httpx.get(f"{srv.url}/api/env").status_code == 401  # signed-in users only
    out = cli("env", "--server", srv.url, "--token", token)
    assert out.returncode == 0, out.stderr
    assert "labtools" in out.stdout and "1.2" in out.stdout and "numpy" in out.stdout


def test_the_libraries_page_lists_the_environment(server):
    srv, token = server
    with httpx.Client(base_url=srv.url, timeout=30) as c:
        nonce = CSRF.search(c.get("/signin").text).group(1)
        assert c.post("/signin", data={"csrf": nonce, "token": token}).status_code == 303
        page = c.get("/env")
        assert page.status_code == 200
        assert "labtools" in page.text and "1.2" in page.text and "is not in the lab's script environment" in page.text
        assert 'href="/env"' in c.get("/submit").text


def test_verify_rejects_an_import_outside_the_environment(tmp_path, env):
    script = tmp_path / "uses_torch.py"
    script.write_text("import torch\n" + USES_THE_ENV)
    out = cli("verify", str(script), "--script-env", str(env), "--runs", "1", "--robots", "2", "--duration", "0.5",
              "--paced-runs", "0")
    assert out.returncode == 1, out.stdout + out.stderr
    assert refusal("torch") in out.stdout


def test_a_bad_script_env_is_a_usage_error(tmp_path):
    out = cli("verify", str(tmp_path / "x.py"), "--script-env", str(tmp_path), "--runs", "1")
    assert out.returncode == 2 and "not a virtual environment" in out.stderr
    out = cli("server", "--data", str(tmp_path / "d"), "--script-env", str(tmp_path / "nope"))
    assert out.returncode == 2 and "no such folder" in out.stderr


def test_env_lists_a_local_environment_and_creates_one(tmp_path, env):
    out = cli("env", "--script-env", str(env), "--json")
    assert out.returncode == 0, out.stderr
    assert {"name": "labtools", "version": "1.2"} in json.loads(out.stdout)["packages"]
    out = cli("env", "create", str(tmp_path / "made"))
    assert out.returncode == 0, out.stderr
    assert "swarmdeck server --script-env" in out.stdout
