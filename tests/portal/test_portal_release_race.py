"""A release of the stopped arena that lands while the arena thread is between its checks never starts a job
with robots still on the floor: the robots return to the chargers first, then the job is claimed.

(Before the fix, the thread saw the arena stopped — no return — and then, released a moment later, claimed the
next job at once: its set-up began from wherever the robots had stopped. tests/portal/test_portal_fleet_upkeep.py hit it
about one run in ten.)"""
import pytest

from swarmdeck.console.portal.runner import ArenaRunner, ArenaSettings
from swarmdeck.console.sandbox.confinement import probe

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")


def test_a_release_between_the_checks_does_not_start_a_job_before_the_return(portal):
    svc = portal.service
    runner = ArenaRunner(svc, ArenaSettings(fast=True, fleet=3, seed=5), poll_s=0.01)
    svc.arena = runner
    # robots left on the floor by an interrupted job
    result, _ = runner.fleet.set_up(99, runner.fleet.start_poses(2), stop=lambda: False, on_loop=lambda loop: None)
    assert result.ok
    runner.fleet.end_assignment()
    on_floor = runner.fleet.away()
    assert len(on_floor) == 2
    svc.arena_needs_operator("test: robots left on the floor")  # stopped, as after an emergency stop
    jid = portal.submit("alice", source="def experiment(arena):\n    arena.step()\n", robots=1, duration=0.1).json()["id"]
    with svc.db.transaction() as tx:
        for state, extra in (("verifying", {}), ("awaiting approval", {"verdict": "accepted"}), ("in arena queue", {})):
            svc.db.transition(tx, jid, state, **extra)

    between = runner._between_jobs

    def then_released() -> bool:  # the operator's release lands right after the thread's check
        tidy = between()
        with svc.db.transaction() as tx:
            svc.db.set_setting(tx, "arena_stopped", "0")
        runner._stop.set()  # one pass of the arena thread
        return tidy

    runner._between_jobs = then_released
    runner._run()
    assert svc.job_state(jid) == "in arena queue"  # not claimed on the pass that saw the arena stopped
    assert runner.fleet.away() == on_floor  # and nobody moved
