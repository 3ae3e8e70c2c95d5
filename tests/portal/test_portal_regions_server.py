"""``swarmdeck server --regions LAYOUT``: the portal's floor divided into regions from the command line; a bad layout
is one line naming what is wrong."""
import subprocess

import httpx
from portal_fixtures import CLI, ServerProcess


def test_the_server_runs_its_floor_as_regions(tmp_path):
    data = tmp_path / "data"
    out = subprocess.run([*CLI, "users", "add", "olga", "--role", "operator", "--data", str(data)],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    token = out.stdout.strip().split()[-1]
    server = ServerProcess(data, "--robots", "6", "--fast", "--regions", "2x1")
    try:
        with httpx.Client(base_url=server.url, headers={"Authorization": f"Bearer {token}"}, timeout=30) as c:
            arena = c.get("/api/operator/arena").json()
        fleet = arena["fleet"]
        assert sorted(fleet["regions"]) == ["r0c0", "r0c1"] and fleet["floor"]["outside"] == 0
        assert all(len(r["free_robots"]) == 3 for r in fleet["regions"].values())
    finally:
        server.stop()


def test_a_bad_layout_is_one_line(tmp_path):
    out = subprocess.run([*CLI, "server", "--data", str(tmp_path / "d"), "--port", "0", "--regions", "9x1"],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 2, out.stderr
    assert "approach area" in out.stderr and "Traceback" not in out.stderr
    out = subprocess.run([*CLI, "server", "--data", str(tmp_path / "d"), "--regions", "2x1", "--robots-via",
                          "mqtt://127.0.0.1:1"], capture_output=True, text=True, timeout=120)
    assert out.returncode == 2 and "does not combine with --robots-via" in out.stderr


def test_an_arena_of_the_lab_divided_into_regions(tmp_path):
    data = tmp_path / "data"
    out = subprocess.run([*CLI, "users", "add", "olga", "--role", "operator", "--data", str(data)],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    token = out.stdout.strip().split()[-1]
    server = ServerProcess(data, "--arena", "big=sim,robots=6,fast,regions=2x1", "--arena", "small=sim,robots=2,fast")
    try:
        with httpx.Client(base_url=server.url, headers={"Authorization": f"Bearer {token}"}, timeout=30) as c:
            arenas = {a["name"]: a for a in c.get("/api/arenas").json()}
            assert [(g["name"], g["robots"], g["stopped"]) for g in arenas["big"]["regions"]] == [
                ("r0c0", 3, False), ("r0c1", 3, False)]
            assert arenas["big"]["slots"] == 2 and arenas["small"]["regions"] is None
            assert c.post("/api/operator/arenas/big/regions/r0c1/estop").json()["regions"][1]["stopped"] is True
    finally:
        server.stop()


def test_regions_with_several_arenas_must_say_which(tmp_path, capsys):
    from swarmdeck.console.cli import main

    assert main(["server", "--data", str(tmp_path / "d"), "--port", "0", "--regions", "2x1",
                 "--arena", "a=sim", "--arena", "b=sim"]) == 2
    err = capsys.readouterr().err
    assert "regions=2x2" in err and "Traceback" not in err, err
    assert main(["server", "--data", str(tmp_path / "d"), "--port", "0", "--arena", "a=sim,robots=2,regions=2x2"]) == 2
    err = capsys.readouterr().err
    assert "no robot" in err and "Traceback" not in err, err
