"""A two-faced script cannot collide robots on the arena: it holds still while it measures pose jitter and tick
timing (verification adds tracking noise and runs as fast as it computes; the simulated arena's poses are exact and
its ticks paced at 33 ms), behaves when it thinks it is verified and drives head-on otherwise. Verification says
"may bypass"; the job then waits for an operator; only after the operator approves that bypass does it run without
the barrier — with the guard, which switches the barrier back on before any pair comes closer than the guard
distance, and the result says so."""
import json

import numpy as np
import pytest
from mqtt_broker import wait_until
from portal_fixtures import wait_for_state

from swarmdeck.console.cli._client import job_line
from swarmdeck.console.portal.runner import ArenaRunner, ArenaSettings
from swarmdeck.console.portal.service import BYPASS_VERDICT, BYPASS_WAIT
from swarmdeck.console.portal.workers import VerificationWorkers
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.executors import SerialExecutor
from swarmdeck.core.kinematics import lookahead_points
from swarmdeck.safety.guard import GuardConfig

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")

TWO_FACED = """
import time
import numpy as np

def experiment(arena):
    seen, stamps = [], []
    for _ in range(8):  # hold still and look
        seen.append(np.array(arena.poses(), dtype=float))
        stamps.append(time.monotonic())
        arena.set_unicycle(np.zeros(arena.n), np.zeros(arena.n))
        arena.step()
    jitter = float(np.max(np.abs(np.diff(np.array(seen), axis=0))))
    tick = float(np.median(np.diff(stamps)))
    watched = jitter > 1e-5 or tick < 0.02
    while True:
        p = np.array(arena.poses(), dtype=float)
        if watched:
            arena.set_unicycle(np.zeros(arena.n), np.zeros(arena.n))
        else:  # head-on: each robot at full speed towards the other
            to = p[::-1, :2] - p[:, :2]
            err = np.angle(np.exp(1j * (np.arctan2(to[:, 1], to[:, 0]) - p[:, 2])))
            arena.set_unicycle(np.full(arena.n, 0.2), 4.0 * err)
        arena.step()
"""
FACING = [[-0.35, 0.0, 0.0], [0.35, 0.0, np.pi]]


@pytest.fixture
def arena(portal):
    workers = VerificationWorkers(portal.service, SerialExecutor(), poll_s=0.2).start()
    runner = ArenaRunner(portal.service, ArenaSettings(fleet=4, seed=3), poll_s=0.2)  # real time, exact poses
    portal.service.arena = runner
    runner.start()
    yield runner
    runner.stop()
    workers.stop()


def test_a_two_faced_script_waits_for_an_operator_then_runs_guarded_and_the_bypass_is_revoked(portal, arena):
    svc = portal.service
    jid = portal.submit("alice", source=TWO_FACED, filename="twofaced.py", duration=3.0, no_barrier=True,
                        initial_poses=FACING).json()["id"]
    with portal.client("alice") as c:
        job = wait_for_state(c, jid, ("awaiting approval", "rejected", "in arena queue"), timeout=120)
        # verification was fooled — and that alone changes nothing: the job waits for a person
        assert job["verdict"] == BYPASS_VERDICT and job["state"] == "awaiting approval", job
        assert job["reason"] == BYPASS_WAIT and job["bypass_pending"]
        assert BYPASS_WAIT in job_line(job)  # what `swarmdeck jobs` prints
    assert svc.job_state(jid) == "awaiting approval" and arena.runs == 0  # manual approval is off: it still waits
    with portal.client("op1") as op:
        page = op.get("/api/operator/arena").json()
        assert page["queue"] == [] and page["alerts"]["messages"] == []
        assert op.post(f"/api/operator/jobs/{jid}/approve").status_code == 409  # a plain approve is not enough
        assert op.post(f"/api/operator/jobs/{jid}/bypass", json={"approve": "yes"}).status_code == 422
        with portal.client("alice") as c:
            assert c.post(f"/api/operator/jobs/{jid}/bypass", json={"approve": True}).status_code == 403
        approved = op.post(f"/api/operator/jobs/{jid}/bypass", json={"approve": True}).json()
        assert approved["state"] in ("in arena queue", "setting up", "running") and approved["bypass_decision"] == "approved"
        audit = op.get("/api/operator/audit").json()
        assert audit[0]["action"] == "approve barrier bypass" and audit[0]["job"] == jid
        assert "S = 1.0000" in audit[0]["detail"]
    with portal.client("alice") as c:
        job = wait_for_state(c, jid, ("done", "failed", "cancelled"), timeout=120)
    assert job["state"] == "done" and job["bypass"] is True, job
    assert "barrier bypass revoked at t = " in job["reason"] and "contact" not in job["reason"]
    run = json.loads((svc.job_dir(jid) / "run.json").read_text())
    revoked = run["bypass"]["revoked"]
    assert run["bypass"]["granted"] and revoked is not None and revoked["t"] > 8 * 0.033 - 1e-9
    assert run["contacts"] == {"count": 0, "robots": [], "episodes": []}
    # the recording: barrier off until the guard tripped, on after it; never a pair below the guard distance
    with open_recording(svc.job_dir(jid) / "recording.mcap") as rec:
        frames = [f for _, f in rec.frames()]
    guard = GuardConfig().guard_distance
    gaps = [np.linalg.norm(np.subtract(*lookahead_points(f.poses, f.lookahead))) for f in frames]
    assert min(gaps) >= guard - 1e-9, min(gaps)
    events = [e for f in frames for e in f.events]
    assert sum(e.startswith("BARRIER BACK ON") for e in events) == 1
    flips = [f.params["safety_enabled"] for f in frames]
    assert flips[0] is False and flips[-1] is True and flips == sorted(flips)  # off, then on for good
    moved = max(abs(g - gaps[0]) for g in gaps)
    assert moved > 0.05  # it did attack: the gap closed by more than 5 cm before the guard stopped it
    with portal.client("op1") as op:
        alerts = op.get("/api/operator/arena").json()["alerts"]
        assert alerts["job"] == jid and any(m.startswith("BARRIER BACK ON") for m in alerts["messages"])


def test_a_refused_bypass_runs_with_the_barrier(portal, arena):
    svc = portal.service
    jid = portal.submit("bob", source=TWO_FACED, filename="twofaced.py", duration=1.0, no_barrier=True,
                        initial_poses=FACING).json()["id"]
    with portal.client("op1") as op:
        wait_until(lambda: svc.job_state(jid) == "awaiting approval", timeout=120, what="verification")
        refused = op.post(f"/api/operator/jobs/{jid}/bypass", json={"approve": False}).json()
        assert refused["bypass_decision"] == "refused" and refused["barrier_forbidden"]
        assert op.post(f"/api/operator/jobs/{jid}/bypass", json={"approve": True}).status_code == 409
        assert op.get("/api/operator/audit").json()[0]["action"] == "refuse barrier bypass"
    with portal.client("bob") as c:
        job = wait_for_state(c, jid, ("done", "failed"), timeout=120)
    assert job["bypass"] is False and job["state"] == "done"
    with open_recording(svc.job_dir(jid) / "recording.mcap") as rec:
        assert {f.params["safety_enabled"] for _, f in rec.frames()} == {True}
