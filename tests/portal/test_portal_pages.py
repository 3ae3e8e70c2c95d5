"""The portal's pages over real uvicorn: sign-in (CSRF, strict HttpOnly cookie, rate limit), forms refused without
their CSRF token, bad form input shown on the page (never a 500), another researcher's job not found, the live
stream, the video made on first download, the operator's forms and the audit log."""
from __future__ import annotations

import html
import json
import re

import av
import httpx
import numpy as np
import pytest
from portal_fixtures import CSRF, SPIN, sign_in
from recording_synth import simulated_frames, write_synthetic_session

from swarmdeck.console.portal.live import scene_message
from swarmdeck.console.recording.export_video import video_frame_count
from swarmdeck.console.web.scene import robot_colors


def upload(c: httpx.Client, csrf: str | None, fields: dict, filename: str = "spin.py", source: str = SPIN):
    data = dict(fields)
    if csrf is not None:
        data["csrf"] = csrf
    return c.post("/submit", data=data, files={"script": (filename, source.encode())})


GOOD = {"name": "spin", "robots": "2", "duration": "1"}


def test_sign_in_gives_a_strict_httponly_session_and_failed_attempts_are_limited(portal):
    c = httpx.Client(base_url=portal.url, timeout=30)
    assert c.get("/jobs").headers["location"] == "/signin"
    r = c.post("/signin", data={"token": portal.tokens["alice"]})
    assert r.status_code == 403 and "CSRF token is missing or wrong" in r.text  # no CSRF token: refused
    nonce = CSRF.search(r.text).group(1)  # the page offers a fresh form
    r = c.post("/signin", data={"csrf": nonce, "token": portal.tokens["alice"]})
    assert r.status_code == 303 and r.headers["location"] == "/jobs"
    cookie = r.headers["set-cookie"].lower()
    assert "swarmdeck_session=" in cookie and "httponly" in cookie and "samesite=strict" in cookie
    assert "secure" not in cookie  # plain http on loopback
    assert "My jobs" in c.get("/jobs").text
    bad = httpx.Client(base_url=portal.url, timeout=30)
    codes = []
    for _ in range(6):
        nonce = CSRF.search(bad.get("/signin").text).group(1)
        r = bad.post("/signin", data={"csrf": nonce, "token": "sdk_wrong"})
        codes.append(r.status_code)
    assert codes == [401] * 5 + [429]
    assert "too many failed sign-ins" in r.text and "sdk_wrong" not in r.text


def test_forms_without_the_csrf_token_are_refused(portal):
    alice, csrf = sign_in(portal, "alice")
    r = upload(alice, None, GOOD)
    assert r.status_code == 403 and "CSRF token is missing or wrong" in r.text
    assert upload(alice, "forged", GOOD).status_code == 403
    assert portal.service.jobs(portal.service.accounts.user_named("alice")) == []
    op, _ = sign_in(portal, "op1")
    assert op.post("/operator/estop", data={}).status_code == 403
    assert not portal.service.arena_stopped
    r = upload(alice, csrf, GOOD)
    assert r.status_code == 303 and re.fullmatch(r"/jobs/\d+", r.headers["location"])


@pytest.mark.parametrize("fields, filename, status, message", [
    ({**GOOD, "robots": "abc"}, "spin.py", 422, "robots must be an integer, got 'abc'"),
    ({**GOOD, "robots": "99"}, "spin.py", 422, "robots must be between 1 and 6"),
    ({**GOOD, "duration": "-1"}, "spin.py", 422, "duration must be > 0"),
    ({**GOOD, "name": ""}, "spin.py", 422, "give the experiment a name"),
    ({**GOOD, "initial_poses": "0 0\n0.5 0 0"}, "spin.py", 422, "line 1: give three numbers x y θ"),
    ({**GOOD, "initial_poses": "0 0 zero\n0.5 0 0"}, "spin.py", 422, "is not three numbers"),
    (GOOD, "notes.txt", 415, "upload a Python script (.py) or a .zip"),
])
def test_bad_form_input_comes_back_on_the_page(portal, fields, filename, status, message):
    alice, csrf = sign_in(portal, "alice")
    r = upload(alice, csrf, fields, filename)
    assert r.status_code == status and message in html.unescape(r.text), r.text[-2000:]
    assert 'role="alert"' in r.text and "Submit an experiment" in r.text
    assert f'value="{fields["name"]}"' in r.text  # what was typed is kept


def test_a_missing_file_and_an_oversized_one_are_explained(portal):
    alice, csrf = sign_in(portal, "alice")
    r = alice.post("/submit", data={**GOOD, "csrf": csrf})
    assert r.status_code == 422 and "choose the script to upload" in r.text
    r = upload(alice, csrf, GOOD, source="#" * (100 << 10))  # over the fixture's 64 kB
    assert r.status_code == 413


def test_another_researchers_job_is_not_found(portal):
    jid = portal.submit("alice").json()["id"]
    bob, _ = sign_in(portal, "bob")
    for path in (f"/jobs/{jid}", f"/jobs/{jid}/report", f"/jobs/{jid}/live", f"/jobs/{jid}/files/manifest.json",
                 f"/jobs/{jid}/files/video.mp4"):
        r = bob.get(path)
        assert r.status_code == 404, path
    assert "no job" in bob.get(f"/jobs/{jid}").text
    assert httpx.get(f"{portal.url}/jobs/{jid}/live").status_code == 401
    alice, _ = sign_in(portal, "alice")
    page = alice.get(f"/jobs/{jid}").text
    assert "spin" in page and f'href="/jobs/{jid}/files/manifest.json"' in page
    assert alice.get(f"/jobs/{jid}/files/manifest.json").json()["name"] == "spin"


def _run(portal, jid: int, state: str = "running") -> None:
    svc = portal.service
    with svc.db.transaction() as tx:
        for s in ("verifying", "awaiting approval", "in arena queue", "setting up", "running"):
            svc.db.transition(tx, jid, s)
        if state != "running":
            svc.db.transition(tx, jid, state)
    svc.notify()


def test_the_live_stream_sends_the_running_jobs_frames_until_it_ends(portal):
    jid = portal.submit("alice", robots=6).json()["id"]
    _run(portal, jid)
    feed = portal.server.server.config.app.state.live
    frames = list(simulated_frames(n_robots=6, n_ticks=3, dt=0.05, seed=2))
    alice, _ = sign_in(portal, "alice")
    events = []
    with alice.stream("GET", f"/jobs/{jid}/live") as r:
        assert r.status_code == 200 and r.headers["content-type"].startswith("text/event-stream")
        lines = r.iter_lines()
        for line in lines:
            if line.startswith("event: "):
                kind = line[7:]
                data = json.loads(next(lines)[6:])
                events.append((kind, data))
                if kind == "state" and not data["final"]:
                    feed.publish(jid + 1000, frames[0])  # another job's Frame: never sent
                    feed.publish(jid, frames[1])
                elif kind == "frame":
                    assert data["seq"] == feed.latest()[0]
                    with portal.service.db.transaction() as tx:
                        portal.service.db.transition(tx, jid, "done")
                elif kind == "state" and data["final"]:
                    break
    kinds = [k for k, _ in events]
    assert kinds == ["state", "frame", "state"] and events[-1][1] == {"state": "done", "final": True}
    sent = events[1][1]
    assert np.allclose(sent["poses"], frames[1].poses, atol=1e-4) and sent["ids"] == list(range(6))


def test_a_scene_message_is_the_consoles_picture_of_the_frame():
    frame = list(simulated_frames(n_robots=5, n_ticks=2, dt=0.05, seed=1))[-1]
    m = scene_message(frame, 7)
    assert m["seq"] == 7 and m["run_state"] == "running" and m["bounds"] == list(frame.bounds)
    assert m["colours"] == ["#{:02x}{:02x}{:02x}".format(*c) for c in robot_colors(frame)]
    assert len(m["edges"]) == len(frame.coverage.edges) and m["density"].startswith("data:image/png;base64,")
    assert m["virtual"] == [] and m["moved"] == np.flatnonzero(frame.barrier.intervention > 1e-3).tolist()
    json.dumps(m, allow_nan=False)


def test_the_video_is_made_on_the_first_download(portal):
    jid = portal.submit("alice").json()["id"]
    _run(portal, jid)
    write_synthetic_session(portal.service.job_dir(jid) / "recording.mcap", n_robots=2, seconds=1.0, dt=0.05)
    alice, _ = sign_in(portal, "alice")
    r = alice.get(f"/jobs/{jid}/files/video.mp4")  # still running: no video yet
    assert r.status_code == 404 and "once the run is over" in r.text
    with portal.service.db.transaction() as tx:
        portal.service.db.transition(tx, jid, "done")
    assert f'href="/jobs/{jid}/files/video.mp4"' in alice.get(f"/jobs/{jid}").text
    r = alice.get(f"/jobs/{jid}/files/video.mp4")
    assert r.status_code == 200 and r.headers["content-type"] == "video/mp4"
    path = portal.service.job_dir(jid) / "video.mp4"
    assert path.read_bytes() == r.content  # kept for the next download
    with portal.client("alice") as api:  # the JSON API serves the same file
        assert api.get(f"/api/jobs/{jid}/files/video.mp4").content == r.content
    with av.open(str(path)) as v:
        assert v.streams.video[0].codec_context.name == "h264"
        assert sum(1 for _ in v.decode(video=0)) == video_frame_count(0.95, 30.0) == 29


def test_operator_forms_act_and_are_audited(portal):
    op, csrf = sign_in(portal, "op1")
    assert op.post("/operator/approval", data={"csrf": csrf, "manual": "on"}).status_code == 303
    assert portal.service.manual_approval
    a, b = (portal.submit("alice").json()["id"] for _ in range(2))
    svc = portal.service
    with svc.db.transaction() as tx:
        for jid in (a, b):
            svc.db.transition(tx, jid, "verifying")
            svc.db.transition(tx, jid, "awaiting approval", verdict="accepted")
    page = op.get("/operator").text
    assert "Manual approval is ON" in page and f'data-action="approve" data-job="{a}"' in page
    for jid in (a, b):
        assert op.post(f"/operator/jobs/{jid}/approve", data={"csrf": csrf}).status_code == 303
    assert [j.id for j in svc.arena_state(svc.accounts.user_named("op1")).queue] == [a, b]
    assert op.post(f"/operator/jobs/{b}/top", data={"csrf": csrf}).status_code == 303
    assert [j.id for j in svc.arena_state(svc.accounts.user_named("op1")).queue] == [b, a]
    r = op.post(f"/operator/jobs/{a}/approve", data={"csrf": csrf})  # already approved (as if by another operator)
    assert r.status_code == 409 and 'role="alert"' in r.text and "EMERGENCY STOP" in r.text
    assert op.post("/operator/estop", data={"csrf": csrf}).status_code == 303 and svc.arena_stopped
    assert "The arena is STOPPED" in op.get("/operator").text
    audit = op.get("/operator/audit").text
    for action in ("manual approval on", "approve", "move", "emergency stop"):
        assert f"<td>{action}</td>" in audit
    alice, _ = sign_in(portal, "alice")
    assert alice.get("/operator").status_code == 403 and alice.get("/operator/audit").status_code == 403
    assert alice.post("/operator/estop", data={"csrf": alice.get("/api/me").json()["csrf"]}).status_code == 403


def test_an_account_disabled_mid_session_is_signed_out_at_its_next_request(portal):
    alice, csrf = sign_in(portal, "alice")
    jid = portal.submit("alice").json()["id"]
    assert alice.get("/jobs").status_code == 200
    portal.service.accounts.disable("alice")
    for r in (alice.get("/jobs"), alice.get(f"/jobs/{jid}"), upload(alice, csrf, GOOD)):
        assert r.status_code == 303 and r.headers["location"] == "/signin"
    assert alice.get(f"/jobs/{jid}/live").status_code == 401
    assert len(portal.service.jobs(portal.service.accounts.user_named("op1"))) == 1  # nothing was submitted
