"""A researcher's results (issue 26 item 17): a summary on the job page, in the API and at the end of `swarmdeck
submit --wait` (did the barrier step in, how often, on which robots; the minimum distance; contacts; the files;
the download command); the script's output live while the job runs (owner and operators only); no density layer
under a script's robots; run.json names no server path; the simulated arena's set-up is paced unless --fast."""
from __future__ import annotations

import json
import subprocess

import pytest
from mqtt_broker import wait_until
from portal_fixtures import CLI, sign_in, skip_verification, wait_for_state

from swarmdeck.console.portal.runner import ArenaRunner, ArenaSettings
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.sandbox.confinement import probe

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")

TOWARDS = ("import numpy as np\n"
           "def experiment(arena):\n"
           "    print('hello from the script', flush=True)\n"
           "    arena.set_goals(np.array([[0.4, 0.0], [-0.4, 0.0]]))  # swap places: head-on\n"
           "    while True:\n"
           "        arena.step()\n")
FACING = [[-0.4, 0.0, 0.0], [0.4, 0.0, 3.14159]]
CHATTY = ("import time\n"
          "def experiment(arena):\n"
          "    print('started, step 0', flush=True)\n"
          "    k = 0\n"
          "    while True:\n"
          "        arena.step()\n"
          "        k += 1\n"
          "        if k == 30:\n"
          "            print('thirty steps in', flush=True)\n")
CRASH_LATE = "def experiment(arena):\n    for _ in range(5):\n        arena.step()\n    raise KeyError('late')\n"


def queued(portal, who, source, **kwargs):  # noqa: F811
    r = portal.submit(who, source=source, **kwargs)
    assert r.status_code == 201, r.text
    jid = r.json()["id"]
    skip_verification(portal, jid)
    return jid


def runner_for(portal, **settings):  # noqa: F811
    runner = ArenaRunner(portal.service, ArenaSettings(**settings), poll_s=0.1)
    portal.service.arena = runner
    return runner.start()


def test_the_results_say_whether_the_barrier_stepped_in_and_how_close_robots_came(portal):  # noqa: F811
    runner = runner_for(portal, fast=True, fleet=4, seed=5)
    try:
        jid = queued(portal, "alice", TOWARDS, robots=2, duration=4.0, initial_poses=FACING)
        crash = queued(portal, "alice", CRASH_LATE, filename="late.py", robots=2, duration=2.0)
        with portal.client("alice") as c:
            wait_for_state(c, jid, ("done",), timeout=120)
            wait_for_state(c, crash, ("failed",), timeout=120)
            summary = c.get(f"/api/jobs/{jid}/results").json()
            with portal.client("bob") as other:
                assert other.get(f"/api/jobs/{jid}/results").status_code == 404
            run_json = c.get(f"/api/jobs/{crash}/files/run.json").text
            crash_job = c.get(f"/api/jobs/{crash}").json()
        alice, _ = sign_in(portal, "alice")
        try:
            page = alice.get(f"/jobs/{jid}").text
        finally:
            alice.close()
        frames = []
        with open_recording(portal.service.job_dir(jid) / "recording.mcap") as rec:
            frames = [f for _, f in rec.frames()]
    finally:
        runner.stop()
    b = summary["barrier"]
    assert b["ticks"] > 60 and b["stepped_in_ticks"] > 0 and set(b["robots"]) == {"0", "1"}  # head-on: both braked
    assert 0.1 < b["min_distance_m"] < 0.8
    assert summary["contacts"] == {"count": 0, "robots": []}
    assert "recording.mcap" in summary["files"] and summary["command"] == f"swarmdeck results {jid} -o job{jid}/"
    assert '<ul class="results" id="results">' in page and "The barrier stepped in on" in page
    assert f"swarmdeck results {jid} -o job{jid}/" in page
    # no server path in run.json or the reason: the sandbox's folder and the data folder are taken out
    data = str(portal.service.data)
    assert "KeyError: 'late'" in run_json and "/tmp/" not in run_json and data not in run_json, run_json
    assert "/tmp/" not in crash_job["reason"] and data not in crash_job["reason"]
    assert "late.py:4" in crash_job["reason"] and "raise KeyError('late')" in crash_job["reason"]  # their file, line
    # the script's robots run without the console's circling density: none recorded (so none in video and replay)
    assert frames and all(f.density is None for f in frames)


def test_submit_wait_ends_with_the_results(portal, tmp_path):  # noqa: F811
    from swarmdeck.console.portal.workers import VerificationWorkers
    from swarmdeck.console.sandbox.executors import SerialExecutor

    runner = runner_for(portal, fast=True, fleet=4, seed=5)
    workers = VerificationWorkers(portal.service, SerialExecutor(), poll_s=0.2).start()
    try:
        script = tmp_path / "towards.py"
        script.write_text(TOWARDS)
        manifest = tmp_path / "m.json"
        manifest.write_text(json.dumps({"name": "towards", "robots": 2, "duration": 3.0, "initial_poses": FACING}))
        out = subprocess.run([*CLI, "submit", str(script), "--manifest", str(manifest), "--wait", "--server",
                              portal.url, "--token", portal.tokens["alice"]], capture_output=True, text=True,
                             timeout=300)
    finally:
        workers.stop()
        runner.stop()
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert any(line.strip().startswith("The barrier stepped in on") for line in lines), out.stdout
    assert any("Minimum distance between robot centres" in line for line in lines)
    assert any("No contact between robots." in line for line in lines)
    assert lines[-1].strip().startswith("Download them: swarmdeck results ")


def test_the_script_output_is_live_for_its_owner_and_operators_only(portal):  # noqa: F811
    runner = runner_for(portal, fleet=4, seed=5)  # real time: the job runs while we read
    try:
        jid = queued(portal, "alice", CHATTY, robots=2, duration=60.0)
        with portal.client("alice") as c:
            wait_for_state(c, jid, ("running",), timeout=120)
            seen = {}

            def printed() -> bool:
                seen.update(c.get(f"/api/jobs/{jid}/log").json())
                return "thirty steps in" in seen["text"]

            wait_until(printed, timeout=60, what="the script's output")
            assert seen["live"] is True and seen["text"].startswith("started, step 0")
            later = c.get(f"/api/jobs/{jid}/log", params={"since": seen["next"]}).json()
            assert later["next"] >= seen["next"] and "started" not in later["text"]  # only what is new
            with portal.client("bob") as other:
                assert other.get(f"/api/jobs/{jid}/log").status_code == 404
            with portal.client("op1") as op:
                assert "thirty steps in" in op.get(f"/api/jobs/{jid}/log").json()["text"]
            alice, _ = sign_in(portal, "alice")
            try:
                page = alice.get(f"/jobs/{jid}").text
            finally:
                alice.close()
            assert 'id="script-log"' in page and "/static/log.js" in page
            assert c.post(f"/api/jobs/{jid}/cancel").status_code == 200
            wait_for_state(c, jid, ("cancelled",), timeout=60)
            wait_until(lambda: "run.json" in {f["name"] for f in c.get(f"/api/jobs/{jid}/files").json()},
                       timeout=120, what="the robots' return and run.json")
            ended = c.get(f"/api/jobs/{jid}/log").json()
            assert "thirty steps in" in ended["text"] and ended["live"] is False
        run = json.loads((portal.service.job_dir(jid) / "run.json").read_text())
    finally:
        runner.stop()
    setup = run["setup"]
    assert setup["ok"] and setup["wall_s"] >= 0.9 * setup["seconds"]  # paced: the simulated set-up in real time
