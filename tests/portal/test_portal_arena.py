"""The arena runner behind the API: the running job's Frames on the LiveFeed, a researcher's cancel and an
operator's emergency stop end it at once (the arena then stays stopped until released; the stop is in the
recording and its exports), and the barrier is
bypassed only when verification allowed it, the manifest asked, no operator forbade it and an operator approved
that job's bypass."""
import csv
import json

import pytest
from mqtt_broker import wait_until
from portal_fixtures import wait_for_state

from swarmdeck.console.portal.runner import ArenaRunner, ArenaSettings
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.sandbox.confinement import probe

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")


@pytest.fixture
def arena(portal):
    runner = ArenaRunner(portal.service, ArenaSettings(fleet=6, seed=4), poll_s=0.2)  # real time
    portal.service.arena = runner
    runner.start()
    yield runner
    runner.stop()


def verified(portal, who, verdict="accepted", decision=None, **kwargs):
    """Submit and move the job to `waiting` as a verification with ``verdict`` would (and an operator's
    ``decision`` on its bypass)."""
    svc = portal.service
    jid = portal.submit(who, **kwargs).json()["id"]
    with svc.db.transaction() as tx:
        svc.db.transition(tx, jid, "verifying")
        svc.db.transition(tx, jid, "awaiting approval", verdict=verdict)
        svc.db.transition(tx, jid, "in arena queue", bypass_decision=decision)
    svc.notify()
    return jid


def frames_of(portal, jid):
    with open_recording(portal.service.job_dir(jid) / "recording.mcap") as rec:
        return [f for _, f in rec.frames()]


def test_an_emergency_stop_ends_the_run_and_holds_the_arena_until_released(portal, arena):
    long = verified(portal, "alice", duration=30.0)
    nxt = verified(portal, "bob", duration=0.3)
    with portal.client("alice") as c:
        wait_for_state(c, long, ("running",))
    seq, job, frame = wait_until(lambda: (x := arena.live.latest()) and x[2] is not None and x[2].tick > 3 and x,
                                 what="live frames")
    assert job == long and frame.poses.shape == (2, 3)
    with portal.client("op1") as op:
        state = op.post("/api/operator/estop").json()
        assert state["stopped"] is True
        wait_until(lambda: arena.current_job is None, what="the run to end")
        job = op.get(f"/api/jobs/{long}").json()
        assert job["state"] == "cancelled" and job["reason"] == "emergency stop by operator op1"
        assert portal.service.job_state(nxt) == "in arena queue"  # the arena stays stopped
        assert op.post("/api/operator/estop").json()["running"] is None
        assert [e["action"] for e in op.get("/api/operator/audit").json()][:2] == ["emergency stop", "emergency stop"]
        assert arena.live.latest()[1] is None
        frames = frames_of(portal, long)
        assert frames[-1].run_time < 29 and json.loads(
            (portal.service.job_dir(long) / "run.json").read_text())["ended_by"] == "cancelled"
        # the stop is in the recording: its last tick is e-stopped with zero commands, the event recorded
        assert frames[-1].run_state == "estop" and not frames[-1].v.any() and not frames[-1].w.any()
        assert any("EMERGENCY STOP" in f.events for f in frames)
        assert wait_until(lambda: op.get(f"/api/jobs/{long}").json()["exports"] != "writing", timeout=120,
                          what="the exports") and op.get(f"/api/jobs/{long}").json()["exports"] == "ready"
        with open(portal.service.job_dir(long) / "frames.csv") as f:  # and so in its exports
            rows = list(csv.DictReader(f))
        assert rows[-1]["run_state"] == "estop" and "EMERGENCY STOP" in " ".join(r["events"] for r in rows)
        assert op.post("/api/operator/release").json()["stopped"] is False
        assert op.post("/api/operator/release").status_code == 409
    with portal.client("bob") as c:
        assert wait_for_state(c, nxt, ("done",))["bypass"] is False


def test_a_researcher_cancels_a_running_job(portal, arena):
    jid = verified(portal, "alice", duration=30.0)
    with portal.client("alice") as c:
        wait_for_state(c, jid, ("running",))
        wait_until(lambda: (f := arena.live.latest()[2]) is not None and f.tick > 3, what="live frames")
        assert c.post(f"/api/jobs/{jid}/cancel").json()["state"] == "cancelled"
        wait_until(lambda: arena.current_job is None, what="the run to end")
        wait_until(lambda: c.get(f"/api/jobs/{jid}").json()["exports"] == "ready", timeout=120, what="the exports")
        names = {f["name"] for f in c.get(f"/api/jobs/{jid}/files").json()}
        assert {"recording.mcap", "robots.csv", "replay.html", "video.mp4", "run.json", "script.log"} <= names
    assert 0 < frames_of(portal, jid)[-1].run_time < 29


def test_the_barrier_is_bypassed_only_when_everyone_agrees(portal, arena):
    bypass = "accepted, may bypass the barrier"
    with portal.client("op1") as op:
        forbidden = portal.submit("alice", duration=0.3, no_barrier=True).json()["id"]
        assert op.post(f"/api/operator/jobs/{forbidden}/barrier", json={"forbid": True}).json()["barrier_forbidden"]
    cases = {verified(portal, "alice", bypass, "approved", duration=0.3, no_barrier=True): False,  # everyone agrees
             verified(portal, "alice", bypass, duration=0.3, no_barrier=True): True,  # no operator approved it
             verified(portal, "alice", bypass, duration=0.3): True,  # the manifest did not ask
             verified(portal, "alice", "accepted", duration=0.3, no_barrier=True): True}  # verification said no
    svc = portal.service
    with svc.db.transaction() as tx:  # the operator forbade it
        svc.db.transition(tx, forbidden, "verifying")
        svc.db.transition(tx, forbidden, "awaiting approval", verdict=bypass)
        svc.db.transition(tx, forbidden, "in arena queue")
    svc.notify()
    cases[forbidden] = True
    with portal.client("alice") as c:
        for jid, barrier_on in cases.items():
            job = wait_for_state(c, jid, ("done",))
            assert job["bypass"] is (not barrier_on)
            assert {f.params["safety_enabled"] for f in frames_of(portal, jid)} == {barrier_on}


def test_the_operators_view_draws_the_running_job(portal, arena):
    from swarmdeck.console.portal.operator_view import OperatorView

    view = OperatorView(port=0)
    arena.frame_listeners.append(view.offer)
    try:
        jid = verified(portal, "alice", duration=0.5)
        with portal.client("alice") as c:
            wait_for_state(c, jid, ("done",))
        wait_until(lambda: view.viewer.drawn > 0, what="a drawn frame")
        assert view.viewer.errors == 0 and view.url.startswith("http://127.0.0.1:")
    finally:
        view.close()
