"""The Operator page (issue 26 item 16): a Cancel for the running job (not only the arena-wide e-stop), "forbid
running without the barrier" as buttons, tables with headers, the audit log's queue positions counted from 1 as
the page counts them, and a picture of the fleet on the arena drawn from /api/operator/arena."""
from __future__ import annotations

import re

import pytest
from mqtt_broker import wait_until
from portal_fixtures import sign_in

from swarmdeck.console.portal.runner import ArenaRunner, ArenaSettings
from swarmdeck.console.sandbox.confinement import probe


def _to(portal, jid, *states, **columns):  # noqa: F811
    svc = portal.service
    with svc.db.transaction() as tx:
        for k, state in enumerate(states):
            svc.db.transition(tx, jid, state, **(columns if k == len(states) - 1 else {}))
    svc.notify()


def test_the_running_job_has_its_own_cancel(portal):  # noqa: F811
    jid = portal.submit("alice").json()["id"]
    _to(portal, jid, "verifying", "awaiting approval", "in arena queue", "setting up", "running")
    op, csrf = sign_in(portal, "op1")
    try:
        page = op.get("/operator").text
        assert re.search(rf'<div id="arena-state">Running:.*data-action="cancel" data-job="{jid}"', page, re.S)
        assert op.post(f"/operator/jobs/{jid}/cancel", data={"csrf": csrf}).status_code == 303
    finally:
        op.close()
    assert portal.service.job_state(jid) == "cancelled" and not portal.service.arena_stopped  # no e-stop needed


def test_forbid_running_without_the_barrier_from_the_page(portal):  # noqa: F811
    svc = portal.service
    jid = portal.submit("alice", no_barrier=True).json()["id"]
    assert svc.claim_for_verification().id == jid
    svc.finish_verification(jid, "accepted, may bypass the barrier", 1.0, [])  # waits for an operator's decision
    op, csrf = sign_in(portal, "op1")
    try:
        page = op.get("/operator").text
        assert f'data-action="forbid-barrier" data-job="{jid}"' in page
        assert op.post(f"/operator/jobs/{jid}/forbid-barrier", data={"csrf": csrf}).status_code == 303
        job = op.get(f"/api/jobs/{jid}").json()
        assert job["barrier_forbidden"] and job["state"] == "in arena queue"  # runs with the barrier
        page = op.get("/operator").text
        assert f'data-action="allow-barrier" data-job="{jid}"' in page
    finally:
        op.close()
    assert svc.accounts.audit_log()[0]["action"] == "forbid barrier bypass"


def test_tables_have_headers_and_the_audit_log_counts_positions_from_1(portal):  # noqa: F811
    svc = portal.service
    with portal.client("op1") as c:
        c.put("/api/operator/settings", json={"manual_approval": True})
    a, b, h = (portal.submit("alice").json()["id"] for _ in range(3))
    _to(portal, a, "verifying", "awaiting approval", "in arena queue")
    _to(portal, b, "verifying", "awaiting approval", "in arena queue")
    _to(portal, h, "verifying", "awaiting approval")
    op, csrf = sign_in(portal, "op1")
    try:
        page = op.get("/operator").text
        approval = page[page.index('<table id="approval">'):]
        assert approval.index("<thead>") < approval.index(f'data-job="{h}"')
        assert "<th>owner</th>" in approval[:approval.index("</thead>")]
        assert op.post(f"/operator/jobs/{b}/top", data={"csrf": csrf}).status_code == 303
        page = op.get("/operator").text
        assert re.search(rf'<tr data-job="{b}"><td>1</td>', page)  # the page: b is first
        op.post(f"/operator/jobs/{h}/hold", data={"csrf": csrf})
        held = op.get("/operator").text
        held = held[held.index('<table id="held">'):]
        assert held.index("<thead>") < held.index(f'data-job="{h}"')
    finally:
        op.close()
    move = next(e for e in svc.accounts.audit_log() if e["action"] == "move")
    assert move["detail"] == "to position 1"  # as the page counts


@pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")
def test_the_fleet_is_drawn_on_the_arena(portal):  # noqa: F811
    runner = ArenaRunner(portal.service, ArenaSettings(fast=True, fleet=4, seed=2), poll_s=0.1)
    portal.service.arena = runner
    runner.start()
    try:
        with portal.client("op1") as c:
            wait_until(lambda: len((c.get("/api/operator/arena").json()["fleet"] or {}).get("robots", [])) == 4,
                       timeout=60, what="the fleet's first reading")
            fleet = c.get("/api/operator/arena").json()["fleet"]
        op, _ = sign_in(portal, "op1")
        try:
            page = op.get("/operator").text
        finally:
            op.close()
    finally:
        runner.stop()
    assert fleet["bounds"] == [-1.6, 1.6, -1.0, 1.0]
    svg = page[page.index('<svg id="arena-map"'):page.index("</svg>")]
    drawn = dict(re.findall(r'data-robot="(\d+)"\s+transform="translate\(([-\d.]+ [-\d.]+)\)', svg))
    assert len(drawn) == 4
    for r in fleet["robots"]:
        x, y = (float(v) for v in drawn[str(r["id"])].split())
        assert abs(x - r["x"]) < 1e-3 and abs(y + r["y"]) < 1e-3  # SVG's y points down
