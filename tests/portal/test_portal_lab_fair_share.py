"""Fair share between researchers (issue 30 item 3): one researcher's batch does not starve the others — jobs
submitted later by someone else interleave with the batch, one job each; with one researcher the queue stays
first come, first served."""
from lab_fixtures import queued


def owners_in_queue(portal):
    return [j.owner for j in portal.service.store.queue()]


def test_a_late_researcher_interleaves_with_a_batch(lab):
    batch = [queued(lab, "alice", robots=2, duration=10.0) for _ in range(6)]
    late = [queued(lab, "bob", robots=2, duration=10.0) for _ in range(2)]
    last = queued(lab, "carol", robots=2, duration=10.0)
    assert owners_in_queue(lab) == ["alice", "bob", "carol", "alice", "bob", "alice", "alice", "alice", "alice"]
    queue = [j.id for j in lab.service.store.queue()]
    assert queue.index(late[0]) == 1 and queue.index(last) == 2 and queue[0] == batch[0]
    # the batch keeps its own order
    assert [q for q in queue if q in batch] == batch


def test_one_researcher_is_first_come_first_served_and_an_operator_can_still_move_jobs(lab):
    ids = [queued(lab, "alice", robots=2, duration=5.0) for _ in range(4)]
    assert [j.id for j in lab.service.store.queue()] == ids
    with lab.client("op1") as op:
        assert op.post(f"/api/operator/jobs/{ids[3]}/move", json={"position": 0}).status_code == 200
    assert [j.id for j in lab.service.store.queue()] == [ids[3], *ids[:3]]


def test_a_job_that_started_leaves_the_fair_share_head(lab):
    svc = lab.service
    first = queued(lab, "alice", robots=2, duration=5.0)
    assert svc.claim_for_arena(arena="floor").id == first
    a2 = queued(lab, "alice", robots=2, duration=5.0)
    b1 = queued(lab, "bob", robots=2, duration=5.0)
    assert [j.id for j in svc.store.queue()] == [a2, b1]  # alice's running job does not count against her
