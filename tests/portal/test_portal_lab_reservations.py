"""Reservations (issue 30 item 3): an operator books an arena for a researcher or a group over a time window;
only their jobs run there then, the queue plans around it; a reservation that overlaps another or lies in the
past is refused naming why."""
import time

from hypothesis import given, settings
from hypothesis import strategies as st
from lab_fixtures import queued

from swarmdeck.console.portal.scheduler import Lane, Pending, Window, plan


def reserve(op, **body):
    return op.post("/api/operator/reservations", json=body)


def test_bad_reservations_are_refused_naming_why(lab):
    now = time.time()
    with lab.client("op1") as op:
        ok = reserve(op, arena="lab", start=now + 100, end=now + 200, user="alice", note="demo")
        assert ok.status_code == 201, ok.text
        for body, status, word in (
                ({"arena": "lab", "start": now + 150, "end": now + 300, "user": "bob"}, 409, "already reserved"),
                ({"arena": "lab", "start": now - 300, "end": now - 200, "user": "bob"}, 422, "in the past"),
                ({"arena": "lab", "start": now + 500, "end": now + 400, "user": "bob"}, 422, "before it starts"),
                ({"arena": "moon", "start": now + 500, "end": now + 600, "user": "bob"}, 404, "no arena"),
                ({"arena": "lab", "start": now + 500, "end": now + 600, "user": "nobody"}, 422, "no user"),
                ({"arena": "lab", "start": now + 500, "end": now + 600}, 422, "either a researcher")):
            r = reserve(op, **body)
            assert r.status_code == status and word in r.json()["error"], (body, r.text)
        # back to back is fine
        assert reserve(op, arena="lab", start=now + 200, end=now + 250, group="swarm").status_code == 201
        assert [r["user"] for r in op.get("/api/reservations").json()] == ["alice", None]
    with lab.client("alice") as c:
        assert reserve(c, arena="floor", start=now + 100, end=now + 200, user="alice").status_code == 403
        assert len(c.get("/api/reservations").json()) == 2  # everyone sees them: the queue plans around them


def test_only_their_jobs_run_in_a_reserved_window_and_the_queue_plans_around_it(lab):
    svc = lab.service
    now = time.time()
    with lab.client("op1") as op:
        assert reserve(op, arena="lab", start=now - 10, end=now + 600, user="alice").status_code == 201
        assert op.put("/api/operator/users/carol/group", json={"group": "swarm"}).json()["group"] == "swarm"
        assert reserve(op, arena="floor", start=now + 300, end=now + 1000, group="swarm").status_code == 201
    bob = queued(lab, "bob", robots=2, duration=30.0, arena="lab")
    alice = queued(lab, "alice", robots=2, duration=30.0, arena="lab")
    with lab.client("bob") as c:
        eta = c.get(f"/api/jobs/{bob}").json()
    assert eta["eta_arena"] == "lab" and eta["eta_start"] >= now + 600  # after alice's window
    assert svc.next_for("lab").id == alice  # bob's job is first in the queue, but the window is alice's
    assert svc.claim_for_arena(arena="lab").id == alice
    # the floor's group window lies ahead: a job that would cross it waits for its end, a short one fits before
    long = queued(lab, "bob", robots=2, duration=400.0, arena="floor")
    short = queued(lab, "bob", robots=2, duration=60.0, arena="floor")
    group = queued(lab, "carol", robots=2, duration=60.0, arena="floor")
    placed = {j.id: j for j in svc.with_eta(svc.store.queue())}
    assert placed[long].eta_start >= now + 1000
    # both short jobs fill the gap before the window (carol's first: fair share puts her first job at the head)
    assert placed[group].eta_start < now + 5 and placed[group].eta_end <= placed[short].eta_start
    assert placed[short].eta_end <= now + 300


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.integers(1, 3), st.floats(1, 200)), max_size=20),
       st.lists(st.tuples(st.sampled_from(["a", "b"]), st.floats(0, 1000), st.floats(10, 300), st.integers(1, 3)),
                max_size=4))
def test_no_planned_job_crosses_a_reservation_that_excludes_its_owner(jobs, windows):
    lanes = [Lane("a", 0, "simulated", 8), Lane("b", 0, "simulated", 8)]
    ws = [Window(arena, start, start + length, frozenset({user})) for arena, start, length, user in windows]
    pending = [Pending(k + 1, user, 2, d) for k, (user, d) in enumerate(jobs)]
    placed = plan(pending, lanes, ws, 0.0, {"a": 5.0, "b": 5.0})
    assert set(placed) == {p.id for p in pending}  # a gap always comes: after the last reservation
    owner = {p.id: p.user_id for p in pending}
    for jid, p in placed.items():
        for w in ws:
            if w.arena == p.arena and owner[jid] not in w.user_ids:
                assert p.end <= w.start or p.start >= w.end, (jid, p, w)
