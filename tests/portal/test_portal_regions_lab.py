"""Regions joined with the lab: an arena's floor divided into regions (``--arena big=sim,robots=12,regions=2x2``) is
planned as one slot per region — the scheduler places each job on a region that holds its robots, several start at
once, the ETAs and claims are the plan's — and an operator's emergency stop of one region takes it out of the plan
until released. No runner here: the claims are made as the region runner's lanes make them."""
import time

import pytest
from lab_fixtures import make_lab, queued
from portal_fixtures import sign_in

from swarmdeck.console.portal.arenas import ArenaSpec, parse_arena_spec
from swarmdeck.console.portal.region_runner import RegionRunner, region_arena
from swarmdeck.console.portal.runner import ArenaSettings
from swarmdeck.devices.fleet.regions import RegionLayout

LAYOUT = RegionLayout.grid(columns=2, rows=2)
BIG = region_arena(parse_arena_spec("big=sim,robots=12,regions=2x2,fast"), LAYOUT)
ARENAS = (BIG, ArenaSpec("small", "simulated", robots=4))


@pytest.fixture
def lab(tmp_path):
    p = make_lab(tmp_path, ARENAS)
    try:
        yield p
    finally:
        p.server.stop()
        p.service.close()


def test_a_region_layout_in_an_arena_spec_and_bad_ones_named():
    spec = parse_arena_spec("big=sim,robots=12,regions=2x2")
    assert (spec.regions, spec.slots) == ("2x2", 4)
    assert BIG.slot_names == ("r0c0", "r0c1", "r1c0", "r1c1") and BIG.slot_robots == (3, 3, 3, 3)
    assert BIG.largest == 3 and BIG.placed_name(1) == "big/r0c1" and BIG.slot_of("big/r1c1") == 3
    assert "regions 2x2 (4 at once)" in BIG.describe()
    for bad, word in (("b=remote,regions=2x2", "in-process simulated"), ("b=sim,regions=2x2,slots=3", "leave out"),
                      ("b=mqtt://127.0.0.1:1883,regions=2x1", "in-process simulated")):
        with pytest.raises(ValueError, match=word):
            parse_arena_spec(bad)
    with pytest.raises(ValueError, match="no robot"):
        region_arena(ArenaSpec("b", robots=3), LAYOUT)  # 4 regions, 3 robots


def test_jobs_are_planned_one_per_region_at_once_and_claimed_per_region(lab):
    svc = lab.service
    jobs = [queued(lab, who, robots=2, duration=30.0, arena="big") for who in ("alice", "bob", "carol", "alice",
                                                                              "bob")]
    now = time.time()
    p = svc.plan(svc.store.queue(), now)
    starting = [j for j in jobs if p[j].start <= now]
    assert len(starting) == 4 and sorted(p[j].slot for j in starting) == [0, 1, 2, 3]
    later = next(j for j in jobs if j not in starting)
    assert p[later].start >= now + 30.0  # after a region's job: duration + the arena's set-up/return estimate
    claimed = {}
    for k, region in enumerate(BIG.slot_names):
        job = svc.claim_for_arena(lambda j: None, arena="big", slot=k)
        assert job is not None, region
        claimed[region] = job.id
        assert svc.store.get(job.id).placed == f"big/{region}"
    assert sorted(claimed.values()) == sorted(starting)
    assert svc.claim_for_arena(lambda j: None, arena="big", slot=0) is None  # every region busy: the fifth waits
    eta = {j.id: j for j in svc.with_eta(svc.store.queue())}[later]
    assert eta.eta_arena == "big" and eta.eta_start is not None and eta.eta_start > now
    with lab.client("alice") as c:
        arenas = {a["name"]: a for a in c.get("/api/arenas").json()}
    assert [(g["name"], g["robots"], g["job"]) for g in arenas["big"]["regions"]] == [
        (r, 3, claimed[r]) for r in BIG.slot_names]
    assert arenas["small"]["regions"] is None


def test_a_job_larger_than_every_region_is_refused_at_submission(lab):
    r = lab.submit("alice", robots=4, duration=10.0, arena="big")
    assert r.status_code == 422 and "the largest region holds 3 robots" in r.text, r.text
    assert lab.submit("alice", robots=4, duration=10.0).status_code == 201  # the small arena holds it


def test_a_stopped_region_leaves_the_plan_until_released(lab):
    svc = lab.service
    first = queued(lab, "alice", robots=2, duration=30.0, arena="big")
    with lab.client("op1") as c:
        r = c.post("/api/operator/arenas/big/regions/r0c0/estop")
        assert r.status_code == 200, r.text
        assert [g["stopped"] for g in r.json()["regions"]] == [True, False, False, False]
        assert "not divided" in c.post("/api/operator/arenas/small/regions/r0c0/estop").text
    assert svc.plan(svc.store.queue(), time.time())[first].slot != 0
    assert svc.claim_for_arena(lambda j: None, arena="big", slot=0) is None
    with lab.client("op1") as c:
        assert c.post("/api/operator/arenas/big/regions/r0c0/release").status_code == 200
    assert svc.claim_for_arena(lambda j: None, arena="big", slot=0).id == first


def test_the_operator_page_stops_and_releases_one_region(lab):
    c, csrf = sign_in(lab, "op1")
    try:
        page = c.get("/operator").text
        assert 'id="region-big-r1c0"' in page and "Stop this region" in page
        assert c.post("/operator/arenas/big/regions/r1c0/estop", data={"csrf": "forged"}).status_code == 403
        assert c.post("/operator/arenas/big/regions/r1c0/estop", data={"csrf": csrf}).status_code == 303
        assert "Release region" in c.get("/operator").text
        assert lab.service.regions_state("big")["regions"][2]["stopped"] is True
        assert c.post("/operator/arenas/big/regions/r1c0/release", data={"csrf": csrf}).status_code == 303
    finally:
        c.close()
    assert lab.service.regions_state("big")["regions"][2]["stopped"] is False


def test_after_the_whole_floors_emergency_stop_a_released_region_moves_again(lab):
    runner = RegionRunner(lab.service, ArenaSettings(name="big", fast=True), LAYOUT, 3)  # its lanes not started
    try:
        runner.emergency_stop()
        assert all(runner.floor.stopped(name) for name in LAYOUT.names)
        runner.floor.release("r0c0")  # what the region's return does once the operator released the portal
        assert not runner.floor.stopped("r0c0")  # (failed before: the floor's own latch kept every region stopped)
        assert runner.floor.stopped("r0c1")
    finally:
        runner.stop()
