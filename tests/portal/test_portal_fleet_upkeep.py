"""The portal's simulated arena keeps one fleet between jobs: each job gets charged robots set up at its start
poses (the manifest's or the script's initial conditions) and ends with every robot back on the chargers; a job
needing more charged robots than there are waits, naming them; a set-up that cannot finish fails the job and a
return that cannot finish latches the arena "needs operator" with the robots named (fast mode, small fleets)."""
import json
import math

import numpy as np
import pytest
from mqtt_broker import wait_until
from portal_fixtures import sign_in, skip_verification, wait_for_state

from swarmdeck.console.portal.runner import ArenaRunner, ArenaSettings
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.runtime.fleet_upkeep import UpkeepConfig
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.devices.validation import colliding_pairs

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")

STILL = "def experiment(arena):\n    while True:\n        arena.step()\n"
A_POSES = [[-0.5, 0.2, 0.3], [0.4, -0.1, -1.2]]
B_POSES = [[0.0, 0.5, 1.0], [0.6, 0.4, 3.0], [-0.6, -0.3, -2.0]]
RPS = ("import numpy as np\nimport rps.robotarium as robotarium\n"
       f"ic = np.array({np.asarray(B_POSES).T.tolist()})\n"
       "r = robotarium.Robotarium(number_of_robots=3, initial_conditions=ic, sim_in_real_time=False)\n"
       "for _ in range(15):\n    r.get_poses()\n    r.set_velocities(np.arange(3), np.zeros((2, 3)))\n    r.step()\n"
       "r.call_at_scripts_end()\n")


def start(portal, **settings):
    runner = ArenaRunner(portal.service, ArenaSettings(fast=True, **settings), poll_s=0.1)
    portal.service.arena = runner
    return runner.start()


def waiting(portal, who, source=STILL, **kwargs):
    """Submit and move the job to `waiting` as an accepting verification would."""
    jid = portal.submit(who, source=source, **kwargs).json()["id"]
    skip_verification(portal, jid)
    return jid


def first_frame_and_collisions(portal, jid):
    with open_recording(portal.service.job_dir(jid) / "recording.mcap") as rec:
        frames = [f for _, f in rec.frames()]
        meta = rec.config()
    return frames[0], sum(bool(len(colliding_pairs(f.poses))) for f in frames), meta


def test_two_jobs_start_at_their_poses_with_charged_robots_and_end_docked(portal):
    runner = start(portal, fleet=5, seed=3, charge=(1.0, 0.1, 1.0, 1.0, 1.0))  # robot 1 is nearly empty
    try:
        a = waiting(portal, "alice", robots=2, duration=0.3, initial_poses=A_POSES)
        b = waiting(portal, "bob", source=RPS, filename="rps_still.py", robots=3, duration=5.0)
        with portal.client("bob") as c:
            assert wait_for_state(c, b, ("done", "failed"))["state"] == "done", c.get(f"/api/jobs/{b}").json()
        used = set()
        for jid, goals in ((a, A_POSES), (b, B_POSES)):
            assert portal.service.job_state(jid) == "done"
            run = json.loads((portal.service.job_dir(jid) / "run.json").read_text())
            setup, back = run["setup"], run["return"]
            assert setup["ok"] and back["ok"], run
            assert setup["collisions"] == back["collisions"] == 0
            assert setup["max_position_error"] < 0.02 and setup["max_heading_error_deg"] < 5.0
            assert setup["seconds"] > 0 and back["seconds"] > 0 and sorted(back["robots"]) == sorted(setup["robots"])
            first, collisions, meta = first_frame_and_collisions(portal, jid)
            g = np.asarray(goals)
            assert first.ids.tolist() == list(range(len(g)))  # the script's N robots, not the fleet
            assert np.all(np.hypot(*(first.poses[:, :2] - g[:, :2]).T) < 0.02), (first.poses, g)
            assert np.all(np.abs(np.angle(np.exp(1j * (first.poses[:, 2] - g[:, 2])))) < math.radians(5))
            assert collisions == 0
            assert meta["config"]["fleet_ids"] == setup["robots"]
            used |= set(setup["robots"])
        assert 1 not in used  # the low battery is never assigned
        browser, _ = sign_in(portal, "alice")
        page = browser.get(f"/jobs/{a}").text
        browser.close()
        assert "Set up at the start poses in" in page and "Returned to the chargers in" in page
        assert "0 collisions" in page
        status = runner.fleet_status()
        assert status["ready"] and status["docked"] == 5 and status["assigned"] == {}
        assert {r["state"] for r in status["robots"]} <= {"docked", "charging"}
        with portal.client("op1") as op:  # the operator's JSON API and page show the fleet
            fleet = op.get("/api/operator/arena").json()["fleet"]
            assert fleet["ready"] and [r["id"] for r in fleet["robots"]] == [0, 1, 2, 3, 4]
            assert fleet["robots"][1]["charge"] < 0.2
        browser, _ = sign_in(portal, "op1")
        page = browser.get("/operator").text
        browser.close()
        assert 'id="fleet"' in page and "Arena ready" in page
    finally:
        runner.stop()


def test_a_job_needing_more_charged_robots_waits_naming_them_until_they_charge(portal):
    runner = start(portal, fleet=3, seed=1, charge=(1.0, 0.1, 1.0))
    try:
        jid = waiting(portal, "alice", robots=3, duration=0.2)
        with portal.client("alice") as c:
            job = wait_until(lambda: (j := c.get(f"/api/jobs/{jid}").json())["reason"] and j, what="a reason")
            assert job["state"] == "in arena queue"
            assert "waiting for robots" in job["reason"] and "robot 1: battery 10% < 50%" in job["reason"]
            with portal.client("op1") as op:
                assert op.get("/api/operator/arena").json()["queue"][0]["reason"] == job["reason"]
            runner.fleet.idle(4 * 3600.0)  # four hours on the strip
            done = wait_for_state(c, jid, ("done", "failed"))
        assert done["state"] == "done" and done["reason"].startswith("set up: done"), done  # no longer "in arena queue"
        run = json.loads((portal.service.job_dir(jid) / "run.json").read_text())
        assert sorted(run["setup"]["robots"]) == [0, 1, 2] and run["return"]["ok"]
        assert runner.fleet_status()["ready"]
    finally:
        runner.stop()


def test_a_start_pose_on_a_docked_robot_fails_the_job_and_nothing_moves(portal):
    runner = start(portal, fleet=4, seed=2, charge=(1.0, 1.0, 1.0, 0.1))  # robot 3 stays on its charger
    try:
        docked = runner.fleet_status()["robots"] or wait_until(lambda: runner.fleet_status()["robots"], what="fleet")
        on_robot_3 = [docked[3]["x"], docked[3]["y"] + 0.05, 0.0]
        jid = waiting(portal, "alice", robots=2, duration=0.2, initial_poses=[[0.0, 0.0, 0.0], on_robot_3])
        with portal.client("alice") as c:
            job = wait_for_state(c, jid, ("done", "failed"))
        assert job["state"] == "failed" and job["reason"].startswith("set-up refused:"), job
        assert "robot 3" in job["reason"], job["reason"]
        assert runner.fleet_status()["ready"] and runner.fleet_status()["docked"] == 4
    finally:
        runner.stop()


def test_setup_and_return_that_cannot_finish_stop_the_robots_and_call_the_operator(portal):
    runner = start(portal, fleet=3, seed=5, upkeep=UpkeepConfig(time_limit=1.0))  # 1 s: nobody gets anywhere
    try:
        jid = waiting(portal, "alice", robots=2, duration=0.2)
        with portal.client("alice") as c:
            job = wait_for_state(c, jid, ("done", "failed"))
        assert job["state"] == "failed" and job["reason"].startswith("set-up failed: set up did not finish within 1 s")
        assert "every robot stopped" in job["reason"]
        with portal.client("op1") as op:
            arena = wait_until(lambda: (x := op.get("/api/operator/arena").json())["needs_operator"] and x,
                               what="needs operator")
            assert arena["stopped"] and "return to the chargers" in arena["needs_operator"]
            away = [r["id"] for r in arena["fleet"]["robots"] if r["state"] == "away"]
            assert away and all(f"robot {i}" in arena["needs_operator"] for i in away), arena
            assert not arena["fleet"]["ready"]
            browser, _ = sign_in(portal, "op1")
            page = browser.get("/operator").text
            browser.close()
            assert "NEEDS AN OPERATOR" in page and "Arena NOT ready" in page
            nxt = waiting(portal, "bob", robots=1, duration=0.2)
            assert portal.service.job_state(nxt) == "in arena queue"  # the arena takes no job
            assert op.post("/api/operator/release").status_code == 200
            assert op.get("/api/operator/audit").json()[0]["action"] == "release emergency stop"
            # released: the arena tries the return again (and, with the same 1 s limit, calls again)
            wait_until(lambda: op.get("/api/operator/arena").json()["needs_operator"], what="needs operator again")
            assert portal.service.job_state(nxt) == "in arena queue"
    finally:
        runner.stop()
