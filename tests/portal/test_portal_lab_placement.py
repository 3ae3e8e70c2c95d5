"""Several arenas behind one portal (issue 30 item 2): a job goes to the arena that fits it first (its robots,
physical/simulated, a named arena); a job no arena can ever run is refused at submission naming why; of arenas
claiming at once, each job runs on exactly one."""
import threading

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from lab_fixtures import queued

from swarmdeck.console.portal.arenas import ArenaSpec, check_unique, parse_arena_spec
from swarmdeck.console.portal.scheduler import Lane, Pending, plan
from swarmdeck.console.portal.states import JobState


def test_arena_specs_parse_and_bad_ones_are_named():
    assert parse_arena_spec("floor=sim,robots=50,fast") == ArenaSpec("floor", "simulated", 50, fast=True)
    assert parse_arena_spec("lab=mqtt://127.0.0.1:1883,robots=20").kind == "physical"
    assert parse_arena_spec("annex=remote,robots=12,kind=physical") == ArenaSpec("annex", "physical", 12, remote=True)
    for bad, word in (("floor", "NAME=SPEC"), ("Floor=sim", "name"), ("f=ftp://x", "sim, mqtt"),
                      ("f=sim,robots=0", "robots"), ("f=sim,kind=physical", "kind="), ("f=sim,colour=red", "colour"),
                      ("f=remote,fast", "fast")):
        with pytest.raises(ValueError, match=word):
            parse_arena_spec(bad)
    with pytest.raises(ValueError, match="two arenas"):
        check_unique([parse_arena_spec("a=sim"), parse_arena_spec("a=remote")])


def test_the_plan_puts_each_job_on_the_arena_that_fits_it_first():
    lanes = [Lane("floor", 0, "simulated", 8), Lane("lab", 0, "physical", 4)]
    jobs = [Pending(1, 1, 6, 30.0), Pending(2, 1, 2, 30.0), Pending(3, 2, 2, 30.0, needs="physical"),
            Pending(4, 2, 2, 30.0, arena="floor"), Pending(5, 2, 9, 30.0)]
    p = plan(jobs, lanes, [], 1000.0, {"floor": 5.0, "lab": 5.0})
    assert (p[1].arena, p[1].start) == ("floor", 1000.0)  # 6 robots: only the floor has them
    assert (p[2].arena, p[2].start) == ("lab", 1000.0)  # the lab is free now
    assert (p[3].arena, p[3].start) == ("lab", 1035.0)  # physical: after job 2 on the lab
    assert (p[4].arena, p[4].start) == ("floor", 1035.0)  # asked for the floor
    assert 5 not in p  # no arena has 9 robots


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.integers(1, 3), st.integers(1, 8), st.floats(1, 100), st.sampled_from(
    ["either", "physical", "simulated"])), max_size=25), st.integers(1, 3))
def test_the_plan_never_overlaps_two_jobs_on_one_lane(jobs, slots):
    lanes = [Lane("floor", k, "simulated", 8) for k in range(slots)] + [Lane("lab", 0, "physical", 4)]
    pending = [Pending(i + 1, u, r, d, needs=n) for i, (u, r, d, n) in enumerate(jobs)]
    p = plan(pending, lanes, [], 0.0, {"floor": 2.0, "lab": 3.0})
    for job in pending:
        fits = [lane for lane in lanes if lane.fits(job)]
        assert (job.id in p) == bool(fits)
    by_lane: dict = {}
    for pl in p.values():
        by_lane.setdefault((pl.arena, pl.slot), []).append((pl.start, pl.end))
        assert pl.start >= 0.0 and pl.end >= pl.start
    for spans in by_lane.values():
        spans.sort()
        assert all(a[1] <= b[0] + 1e-9 for a, b in zip(spans, spans[1:]))


def test_a_job_no_arena_can_run_is_refused_at_submission(lab):
    for extra, field, word in (({"arena": "moon"}, "arena", "no arena 'moon'"),
                               ({"robots": 6, "arena": "lab"}, "robots", "has 4 robots"),
                               ({"robots": 6, "needs": "physical"}, "robots", "no physical arena has 6"),
                               ({"needs": "quantum"}, "needs", "needs must be one of"),
                               ({"arena": "Lab!"}, "arena", "arena must be")):
        r = lab.submit("alice", **extra)
        assert r.status_code == 422, r.text
        assert r.json()["field"] == field and word in r.json()["error"]
    ok = lab.submit("alice", robots=3, needs="physical")
    assert ok.status_code == 201 and ok.json()["needs"] == "physical"


def test_jobs_placed_on_two_arenas_say_where_and_when(lab):
    svc = lab.service
    a = queued(lab, "alice", robots=6, duration=30.0)
    b = queued(lab, "bob", robots=2, duration=30.0, needs="physical")
    with lab.client("alice") as c:
        job = c.get(f"/api/jobs/{a}").json()
    assert job["eta_arena"] == "floor" and job["eta_end"] - job["eta_start"] >= 30.0
    assert svc.next_for("lab").id == b and svc.next_for("floor").id == a
    claimed = svc.claim_for_arena(arena="lab")
    assert claimed.id == b and claimed.placed == "lab" and claimed.state == JobState.SETTING_UP
    with lab.client("op1") as c:
        arenas = {x["name"]: x for x in c.get("/api/arenas").json()}
    assert arenas["lab"]["running"] == [b] and arenas["floor"]["running"] == [] and arenas["lab"]["kind"] == "physical"


def test_arenas_claiming_at_once_run_each_job_exactly_once(lab):
    svc = lab.service
    ids = [queued(lab, who, robots=2, duration=1.0) for who in ("alice", "bob") * 6]
    got: dict[str, list[int]] = {"floor": [], "lab": []}

    def arena(name):
        while True:
            job = svc.claim_for_arena(arena=name)
            if job is None:
                if not svc.store.queue():
                    return
                continue
            got[name].append(job.id)
            svc.mark_running(job.id)
            svc.finish_run(job.id, JobState.DONE, None)

    threads = [threading.Thread(target=arena, args=(n,)) for n in ("floor", "lab", "floor", "lab")]
    for t in threads:
        t.start()
    for t in threads:
        t.join(120)
    ran = got["floor"] + got["lab"]
    assert sorted(ran) == sorted(ids)  # every job once: none lost, none twice
    for name, jobs in got.items():
        assert all(svc.store.get(j).placed == name for j in jobs)
