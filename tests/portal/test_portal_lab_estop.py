"""One arena's emergency stop (issue 30 item 2): it ends that arena's jobs and latches only that arena; the other
arenas keep taking jobs; release lets it take jobs again. The portal-wide stop still stops every arena."""
from lab_fixtures import queued

from swarmdeck.console.portal.states import JobState


def test_stopping_one_arena_leaves_the_others_running(lab):
    svc = lab.service
    on_lab = queued(lab, "alice", robots=2, duration=30.0, arena="lab")
    on_floor = queued(lab, "bob", robots=2, duration=30.0, arena="floor")
    assert svc.claim_for_arena(arena="lab").id == on_lab
    assert svc.claim_for_arena(arena="floor").id == on_floor
    waiting = queued(lab, "carol", robots=2, duration=5.0, arena="lab")
    later = queued(lab, "carol", robots=2, duration=5.0)
    with lab.client("op1") as op:
        state = op.post("/api/operator/arenas/lab/estop").json()
        assert {a["name"]: a["stopped"] for a in state["arenas"]} == {"floor": False, "lab": True}
        assert op.post("/api/operator/arenas/moon/estop").status_code == 404
        assert op.post("/api/operator/arenas/floor/release").status_code == 409  # not stopped
    assert svc.job_state(on_lab) == JobState.CANCELLED and "emergency stop" in svc.store.get(on_lab).reason
    assert svc.job_state(on_floor) == JobState.SETTING_UP
    assert svc.claim_for_arena(arena="lab") is None  # latched
    svc.mark_running(on_floor)
    svc.finish_run(on_floor, JobState.DONE, None)
    assert svc.claim_for_arena(arena="floor").id == later  # the lab's job waits for the lab
    with lab.client("op1") as op:
        assert op.post("/api/operator/arenas/lab/release").json()["arenas"][1]["stopped"] is False
    assert svc.claim_for_arena(arena="lab").id == waiting
    with lab.client("op1") as op:
        op.post("/api/operator/estop")
    assert svc.job_state(waiting) == JobState.CANCELLED and svc.job_state(later) == JobState.CANCELLED
    assert [e["action"] for e in svc.audit_log(svc.accounts.user_named("op1"))][:3] == [
        "emergency stop", "release emergency stop of arena lab", "emergency stop of arena lab"]


def test_the_operator_page_lists_the_arenas_with_their_own_stop(lab):
    from portal_fixtures import sign_in

    job = queued(lab, "alice", robots=2, duration=30.0, arena="lab")
    c, csrf = sign_in(lab, "op1")
    try:
        page = c.get("/operator").text
        assert 'id="arenas"' in page and 'id="arena-floor"' in page and 'action="/operator/arenas/lab/estop"' in page
        r = c.post("/operator/arenas/lab/estop", data={"csrf": csrf})
        assert r.status_code in (200, 303)
        assert lab.service.store.arena_stopped_named("lab") and not lab.service.store.arena_stopped()
        page = c.get("/operator").text
        assert 'action="/operator/arenas/lab/release"' in page
        assert c.post("/operator/arenas/lab/release", data={"csrf": "forged"}).status_code == 403
        assert lab.service.store.arena_stopped_named("lab")
    finally:
        c.close()
    with lab.client("alice") as researcher:
        assert researcher.post("/api/operator/arenas/lab/release").status_code == 403
    assert lab.service.job_state(job) == "in arena queue"
