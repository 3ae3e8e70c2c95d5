"""`swarmdeck fleet status --server URL` shows the portal's fleet: the robots assigned to the running job, the
docked ones with their charge, and the arena ready again once the job ended and the robots returned."""
import json

import pytest
from mqtt_broker import wait_until
from portal_fixtures import SPIN, skip_verification, wait_for_state

from swarmdeck.console.cli import main
from swarmdeck.console.portal.runner import ArenaRunner, ArenaSettings
from swarmdeck.console.sandbox.confinement import probe

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")


def status(portal, capsys, who="op1", *extra):
    code = main(["fleet", "status", "--server", portal.url, "--token", portal.tokens[who], *extra])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_fleet_status_through_the_server_shows_the_assigned_robots(portal, capsys):
    runner = ArenaRunner(portal.service, ArenaSettings(fleet=4, seed=6), poll_s=0.1)  # the job in real time
    portal.service.arena = runner
    runner.start()
    try:
        jid = portal.submit("alice", source=SPIN, robots=2, duration=60.0).json()["id"]  # cancelled long before
        skip_verification(portal, jid)
        with portal.client("alice") as c:
            wait_for_state(c, jid, ("running",))
            code, out, _ = status(portal, capsys, "op1", "--json")
            doc = json.loads(out)
            assert code == 0 and not doc["stopped"] and doc["ready"]  # docked or assigned: ready
            assigned = [r for r in doc["robots"] if r["state"] == "assigned"]
            assert len(assigned) == 2 and {r["job"] for r in assigned} == {jid}
            assert sorted(int(k) for k in doc["assigned"]) == sorted(r["id"] for r in assigned)
            code, out, _ = status(portal, capsys)
            assert code == 0 and out.count(f"assigned to job {jid}") == 2 and "2/4 docked · arena ready" in out
            c.post(f"/api/jobs/{jid}/cancel")
            wait_until(lambda: runner.current_job is None, what="the run to end (robots returned)")
        code, out, _ = status(portal, capsys)
        assert code == 0 and "assigned" not in out and "4/4 docked · arena ready" in out, out
        code, _, err = status(portal, capsys, "alice")  # a researcher's token: not for the fleet
        assert code == 1 and "HTTP 403" in err
        assert main(["fleet", "dock", "--server", portal.url, "--token", "x"]) == 2
    finally:
        runner.stop()
