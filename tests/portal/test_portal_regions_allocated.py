"""Regions allocated per job through the portal (``--arena NAME=sim,robots=N,regions=auto:COLSxROWS``): the plan
puts each job on the smallest region of the floor's guillotine tree that holds its robots — small jobs one leaf each,
at once, a job asking for more robots than a leaf holds on a bigger region (or the whole floor) — never on two
nested regions at once; the ETAs are that plan's, and each job is verified against the region it gets. End to end
on a small floor: a 2-robot job runs in a leaf, a 5-robot job gets the whole floor once the leaf is free."""
import time

import pytest
from lab_fixtures import make_lab, queued
from mqtt_broker import wait_until
from portal_fixtures import make_portal, wait_for_state

from swarmdeck.console.portal.arenas import parse_arena_spec
from swarmdeck.console.portal.exports import JobExports
from swarmdeck.console.portal.region_runner import RegionRunner, region_arena
from swarmdeck.console.portal.runner import ArenaSettings
from swarmdeck.console.portal.states import ACTIVE
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.core.bounds import Bounds
from swarmdeck.devices.fleet.regions import RegionLayout

TREE = RegionLayout.guillotine(columns=4, rows=2)
BIG = region_arena(parse_arena_spec("big=sim,robots=48,regions=auto:4x2,fast"), TREE)


@pytest.fixture
def lab(tmp_path):
    p = make_lab(tmp_path, (BIG,))
    try:
        yield p
    finally:
        p.server.stop()
        p.service.close()


def test_the_plan_gives_each_job_the_smallest_region_that_holds_it_and_never_two_nested_ones(lab):
    svc, names = lab.service, BIG.slot_names
    assert (BIG.regions, BIG.slots) == ("auto:4x2", 15) and names[-1] == "all"
    big = queued(lab, "alice", robots=20, duration=30.0, arena="big")  # more than a leaf or a quarter: a half
    small = [queued(lab, who, robots=4, duration=30.0, arena="big") for who in ("bob", "carol", "bob", "carol", "bob")]
    whole = queued(lab, "carol", robots=40, duration=30.0, arena="big")
    now = time.time()
    p = svc.plan(svc.store.queue(), now)
    half = names[p[big].slot]
    assert half in ("r0-1c0-1", "r0-1c2-3") and p[big].start <= now
    inside = set(TREE.conflicts(half))
    starting = [j for j in small if p[j].start <= now]
    assert len(starting) == 4  # the four leaves of the other half, at once
    assert {names[p[j].slot] for j in starting} == {n for n in TREE.leaves if n not in inside}
    later = next(j for j in small if j not in starting)
    assert p[later].start >= now + 30.0  # after a leaf's job
    assert names[p[whole].slot] == "all" and p[whole].start >= max(p[j].end for j in (big, *starting))
    assert svc.job_bounds(svc.store.get(big)) == Bounds(-0.8, 0.8, -1.0, 1.0)  # verified in the half it gets
    assert svc.job_bounds(svc.store.get(small[0])) == Bounds(-0.4, 0.4, -0.5, 0.5)  # … in a leaf
    claimed = svc.claim_for_arena(lambda j: None, arena="big", slot=names.index(half))
    assert claimed is not None and claimed.id == big and svc.store.get(big).placed == f"big/{half}"
    leaf_inside = next(n for n in TREE.leaves if n in inside)  # the half runs: no region inside it may start
    assert svc.claim_for_arena(lambda j: None, arena="big", slot=names.index(leaf_inside)) is None
    assert svc.claim_for_arena(lambda j: None, arena="big", slot=names.index("all")) is None
    with lab.client("carol") as c:
        eta = {j["id"]: j for j in c.get("/api/jobs").json()}[whole]
    assert eta["eta_arena"] == "big" and eta["eta_start"] == pytest.approx(p[whole].start, abs=5.0)


FLOOR_SCRIPT = ("import numpy as np\n"
                "from swarmdeck.devices import Arena\n"
                "arena = Arena()\n"
                "print('BOUNDS', [round(v, 3) for v in arena.config.bounds])\n"
                "while True:\n"
                "    arena.step_unicycle(np.zeros(arena.n), np.full(arena.n, 0.5))\n")


@pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")
def test_a_job_asking_more_than_a_leaf_gets_the_whole_floor_end_to_end(tmp_path):
    layout = RegionLayout.guillotine(columns=2, rows=1)
    spec = region_arena(parse_arena_spec("arena=sim,robots=6,regions=auto:2x1,fast"), layout)
    portal = make_portal(tmp_path, arenas=(spec,), fleet=6, max_duration=60.0, max_upload_bytes=64 << 10)
    runner = RegionRunner(portal.service, ArenaSettings(fast=True, seed=3), layout, 3, poll_s=0.2,
                          exports=JobExports(portal.service, video=False))
    portal.service.arena = runner
    runner.start()
    try:
        ids = {}
        for who, n in (("alice", 2), ("bob", 5)):
            r = portal.submit(who, source=FLOOR_SCRIPT, filename="job.py", robots=n, duration=2.0)
            assert r.status_code == 201, r.text
            ids[who] = r.json()["id"]
            with portal.service.db.transaction() as tx:
                for state, extra in (("verifying", {}), ("awaiting approval", {"verdict": "accepted"}),
                                     ("in arena queue", {})):
                    portal.service.db.transition(tx, ids[who], state, **extra)
        portal.service.notify()
        for who, jid in ids.items():
            with portal.client(who) as c:
                assert wait_for_state(c, jid, ("done", "failed", "cancelled"), timeout=180)["state"] == "done"
        store = portal.service.store
        assert store.get(ids["alice"]).placed in ("arena/r0c0", "arena/r0c1")
        assert store.get(ids["bob"]).placed == "arena/all"
        with portal.client("bob") as c:
            assert "BOUNDS [-1.6, 1.6, -1.0, 1.0]" in c.get(f"/api/jobs/{ids['bob']}/files/script.log").text
        with portal.client("alice") as c:
            assert "BOUNDS [-0.8, 0.8, -1.0, 1.0]" in c.get(f"/api/jobs/{ids['alice']}/files/script.log").text
        wait_until(lambda: not runner.floor.busy() and not any(portal.service.job_state(j) in ACTIVE
                                                                for j in ids.values()),
                   timeout=120, what="the floor's robots returned")
        assert runner.floor.stats.outside == 0 and runner.floor.ports.report.collision_pairs == 0
    finally:
        runner.stop()
        portal.server.stop()
        portal.service.close()
