"""The portal's web pages: sign-in, the researcher's upload, jobs, job page with the live view, the operator's pages.

:func:`router` gives the routes :func:`~swarmdeck.console.portal.app.create_app`
includes. Pages are rendered on the server (Jinja2 templates in ``templates/``,
autoescaped); ``static/`` holds the stylesheet and three small vanilla scripts
(no CDN, no inline script: the Content-Security-Policy allows only this origin).
Every page calls one :class:`~swarmdeck.console.portal.service.PortalService`
method, as the JSON API does, so the rules (who sees what, the state machine,
the audit log) live in one place.

=======================================  =============================================================
``GET /``                                your jobs (researchers), the operator page (operators), or sign-in
``GET|POST /signin``, ``POST /signout``  the access token → a session (the API's cookie: HttpOnly,
                                         SameSite=Strict, Secure over https); failed sign-ins are
                                         rate-limited by the service
``GET /jobs``                            your jobs and their states (refreshed every 2 s)
``GET|POST /submit``                     upload a script (.py or .zip, its entry file) with the manifest's
                                         fields; every mistake shown at once (``forms.js`` sends the form in
                                         the background so the chosen file stays chosen)
``GET /env``                             the libraries scripts can import (the lab's script environment)
``GET /jobs/{id}``                       state, verdict, the verification report, the live view and the
                                         script's output while it runs (``log.js``), the results in short
                                         when it has ended, downloads, cancel (``POST /jobs/{id}/cancel``)
``GET /jobs/{id}/report``                the verification report page (``console/sandbox/report_html.py``)
``GET /jobs/{id}/live``                  the live view's stream (Server-Sent Events): the runner's
                                         LiveFeed as :func:`~.live.scene_message` JSON, 10 a second at most;
                                         only the job's owner and operators
``GET /jobs/{id}/files/{name}``          downloads (exports appear as they are written; ``video.mp4``, if the
                                         exports did not write it, is rendered on the first request)
``GET /operator``                        queue (approve, hold, release, reorder, cancel, approve or refuse a
                                         job's barrier bypass beside its verdict, S and report), arena state,
                                         EMERGENCY STOP, manual-approval switch (``POST /operator/...``)
``GET /operator/audit``                  the audit log
=======================================  =============================================================

Security: every page but sign-in needs the session cookie (else it redirects to
``/signin``; the live stream answers 401/404). Every form carries a CSRF token
— the session's, or for the sign-in form a one-time value in its own
HttpOnly cookie — and a POST without the right one is refused (403) before
anything is done. A job of somebody else is "not found", as in the API. Bad
input on a form comes back as the same page with the message (4xx), never a 500.
"""
from __future__ import annotations

import asyncio
import hmac
import json
import math
import secrets
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from fastapi import APIRouter, Depends, Request
from fastapi.responses import FileResponse, HTMLResponse, RedirectResponse, Response, StreamingResponse
from jinja2 import Environment, FileSystemLoader, select_autoescape
from starlette.concurrency import run_in_threadpool
from starlette.datastructures import FormData, UploadFile

from swarmdeck.console.portal.accounts import Session
from swarmdeck.console.portal.api import SESSION_COOKIE
from swarmdeck.console.portal.errors import BadInput, PortalError, Unauthorized
from swarmdeck.console.portal.live import scene_message
from swarmdeck.console.portal.livefeed import LiveFeed
from swarmdeck.console.portal.results import summary_lines
from swarmdeck.console.portal.service import PortalService
from swarmdeck.console.portal.states import ACTIVE, FINAL, JobState
from swarmdeck.console.portal.submission import Limits, display_name, manifest_errors
from swarmdeck.console.portal.sweep_job import REPORT_HEADERS
from swarmdeck.core.errors import SwarmdeckError

HERE = Path(__file__).resolve().parent
STATIC = {"portal.css": "text/css", "live.js": "text/javascript", "refresh.js": "text/javascript",
          "forms.js": "text/javascript", "docs.js": "text/javascript", "log.js": "text/javascript",
          "compare.js": "text/javascript"}
SIGNIN_COOKIE = "swarmdeck_signin"
LIVE_PERIOD = 0.1  # s: the live view gets at most 10 Frames a second (the newest at each send)
CHECK_PERIOD = 1.0  # s: the live stream re-checks the session and the job's state this often
CSP = ("default-src 'self'; img-src 'self' data:; style-src 'self'; script-src 'self'; frame-src 'self'; "
       "connect-src 'self'; frame-ancestors 'self'; form-action 'self'; base-uri 'none'")
REPORT_CSP = "default-src 'none'; style-src 'unsafe-inline'; img-src data:; frame-ancestors 'self'"


def _templates() -> Environment:
    env = Environment(loader=FileSystemLoader(str(HERE / "templates")), autoescape=select_autoescape(default=True),
                      trim_blocks=True, lstrip_blocks=True)
    env.filters["when"] = lambda t: "" if t is None else time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(t))
    env.filters["size"] = lambda n: f"{n / 1e6:.1f} MB" if n >= 1e5 else f"{n / 1e3:.1f} kB"
    return env


def router(service: PortalService, live: LiveFeed) -> APIRouter:
    """The pages on ``service``; the live view reads ``live`` (the arena runner's LiveFeed)."""
    env = _templates()
    r = APIRouter(include_in_schema=False)

    # ------------------------------------------------------------------ helpers
    def page(request: Request, name: str, session: Session | None, status: int = 200, **ctx: Any) -> HTMLResponse:
        html = env.get_template(name).render(user=None if session is None else session.user,
                                             csrf="" if session is None else session.csrf, **ctx)
        return HTMLResponse(html, status_code=status, headers={"Content-Security-Policy": CSP,
                                                               "Cache-Control": "no-store",
                                                               "X-Content-Type-Options": "nosniff",
                                                               "Referrer-Policy": "same-origin"})

    async def session_of(request: Request) -> Session | None:
        """The request's web session (None: no cookie, or one signed out, expired or of a disabled account)."""
        sid = request.cookies.get(SESSION_COOKIE)
        if not sid:
            return None
        try:
            return service.accounts.session(sid)
        except Unauthorized:
            return None

    async def signed_in(s: Session | None = Depends(session_of)) -> Session:
        """The dependency of every page behind sign-in: the session, or :class:`SignInRequired` (→ ``/signin``)."""
        if s is None:
            raise SignInRequired()
        return s

    def to_signin() -> RedirectResponse:
        return RedirectResponse("/signin", status_code=303)

    def refused(request: Request, session: Session | None, message: str, status: int) -> HTMLResponse:
        return page(request, "message.html", session, status=status, title="Refused", message=message)

    async def checked_form(request: Request, session: Session) -> FormData | HTMLResponse:
        """The POSTed form when its CSRF token is the session's; else the refusal page (403)."""
        form = await request.form(max_files=1, max_fields=16,
                                  max_part_size=service.config.limits.max_upload_bytes)
        token = form.get("csrf")
        if not isinstance(token, str) or not hmac.compare_digest(token.encode(), session.csrf.encode()):
            await form.close()
            return refused(request, session, "refused: this form's CSRF token is missing or wrong — reload the page "
                                              "and try again", 403)
        return form

    # ------------------------------------------------------------------ sign-in
    @r.get("/")
    def home(request: Request, s: Session = Depends(signed_in)) -> Response:
        return RedirectResponse("/operator" if s.user.is_operator else "/jobs", status_code=303)

    def signin_page(request: Request, message: str | None = None, status: int = 200) -> HTMLResponse:
        nonce = secrets.token_urlsafe(24)
        resp = page(request, "signin.html", None, status=status, nonce=nonce, message=message)
        resp.set_cookie(SIGNIN_COOKIE, nonce, max_age=3600, httponly=True, samesite="strict",
                        secure=request.url.scheme == "https", path="/signin")
        return resp

    @r.get("/signin")
    def signin_form(request: Request) -> HTMLResponse:
        return signin_page(request)

    @r.post("/signin")
    async def signin(request: Request) -> Response:
        form = await request.form(max_files=0, max_fields=4)
        nonce, cookie = form.get("csrf"), request.cookies.get(SIGNIN_COOKIE)
        if not isinstance(nonce, str) or not cookie or not hmac.compare_digest(nonce.encode(), cookie.encode()):
            return signin_page(request, "refused: the sign-in form's CSRF token is missing or wrong — try again "
                                        "from this page", 403)
        token = form.get("token")
        client = request.client.host if request.client else "?"
        try:
            s = await run_in_threadpool(service.accounts.sign_in, str(token or "").strip(), client)
        except PortalError as exc:
            return signin_page(request, exc.message, exc.status)
        resp = RedirectResponse("/operator" if s.user.is_operator else "/jobs", status_code=303)
        resp.set_cookie(SESSION_COOKIE, s.id, max_age=int(service.accounts.session_s), httponly=True,
                        samesite="strict", secure=request.url.scheme == "https", path="/")
        resp.delete_cookie(SIGNIN_COOKIE, path="/signin")
        return resp

    @r.post("/signout")
    async def signout(request: Request, s: Session = Depends(signed_in)) -> Response:
        form = await checked_form(request, s)
        if isinstance(form, Response):
            return form
        service.accounts.sign_out(s.id)
        resp = to_signin()
        resp.delete_cookie(SESSION_COOKIE, path="/")
        return resp

    # ------------------------------------------------------------------ researchers
    @r.get("/jobs")
    def jobs(request: Request, s: Session = Depends(signed_in)) -> Response:
        return page(request, "jobs.html", s, jobs=service.jobs(s.user, mine=True))

    def submit_page(request: Request, s: Session, status: int = 200, errors: list[PortalError] | None = None,
                    values: dict[str, Any] | None = None, chosen: str | None = None) -> HTMLResponse:
        """The Submit page; after a refused submission: every error (each naming its field), the fields as they
        were typed, and the name of the file chosen (a browser cannot put a file back into a file input)."""
        limits = service.config.limits
        errors = errors or []
        return page(request, "submit.html", s, status=status, errors=errors, bad={e.field for e in errors},
                    values=values or {}, chosen=chosen, fleet=limits.fleet, max_duration=limits.max_duration,
                    max_bytes=limits.max_upload_bytes, usage=service.usage(s.user))

    @r.get("/env")
    def environment(request: Request, s: Session = Depends(signed_in)) -> Response:
        try:
            info = service.environment()
        except PortalError as exc:
            return page(request, "message.html", s, status=exc.status, title="Libraries", message=exc.message)
        return page(request, "env.html", s, env=info)

    @r.get("/submit")
    def submit_form(request: Request, s: Session = Depends(signed_in)) -> Response:
        return submit_page(request, s)

    @r.post("/submit")
    async def submit(request: Request, s: Session = Depends(signed_in)) -> Response:
        form = await checked_form(request, s)
        if isinstance(form, Response):
            return form
        values = {k: form.get(k) for k in ("name", "robots", "duration", "initial_poses", "entry", "params")
                  if isinstance(form.get(k), str)}
        values["no_barrier"] = form.get("no_barrier") == "on"
        script = form.get("script")
        chosen = display_name(script.filename) if isinstance(script, UploadFile) and script.filename else None
        try:
            # every mistake in the fields at once (the service would stop at the first)
            errors: list[PortalError] = []
            if chosen is None:
                errors.append(BadInput("choose the script to upload (.py, or a .zip)", "script"))
            manifest, field_errors = manifest_from_form(values, chosen, service.config.limits)
            errors += field_errors
            if errors:
                return submit_page(request, s, 422, errors, values, chosen)
            data = await script.read(service.config.limits.max_upload_bytes + 1)
            job = await run_in_threadpool(service.submit, s.user, script.filename, data, manifest,
                                          (values.get("entry") or "").strip() or None)
        except PortalError as exc:
            return submit_page(request, s, exc.status, [exc], values, chosen)
        finally:
            await form.close()
        return RedirectResponse(f"/jobs/{job.id}", status_code=303)

    @r.get("/jobs/{job_id}")
    def job_page(request: Request, job_id: int, s: Session = Depends(signed_in)) -> Response:
        try:
            job = service.job(s.user, job_id)
            files = service.downloads(s.user, job_id)  # the video too, when it is made on its first download
        except PortalError as exc:
            return refused(request, s, exc.message, exc.status)
        try:
            report = service.report(s.user, job_id)
        except PortalError:
            report = None
        run = service.run_summary(s.user, job_id) if job.state in FINAL else None
        results, sweep = None, None
        if job.state in FINAL and job.state != JobState.REJECTED and not job.results_deleted:
            full = service.results(s.user, job_id)
            results, sweep = summary_lines(full), full.get("sweep")
        others = comparable(s, job_id) if job.state in FINAL and not job.results_deleted else []
        return page(request, "job.html", s, job=job, files=files, report=report, run=run, results=results, sweep=sweep,
                    live=job.state in ACTIVE, final=job.state in FINAL, live_states=ACTIVE, final_states=FINAL,
                    others=others)

    def comparable(s: Session, job_id: int) -> list[Any]:
        """The user's own other ended jobs whose results are kept: what a job can be compared with."""
        return [j for j in service.jobs(s.user, mine=True)
                if j.id != job_id and j.state in FINAL and j.results_deleted is None][:200]

    @r.get("/jobs/{job_id}/compare")
    async def compare_page(request: Request, job_id: int, s: Session = Depends(signed_in)) -> Response:
        """Job ``job_id`` compared with ``?with=K``: the metric table and the two runs overlaid (compare.js)."""
        raw = request.query_params.get("with", "")
        try:
            job = service.job(s.user, job_id)
            if not raw.strip().isdigit():
                raise BadInput(f"choose a job to compare job {job_id} with (?with=JOB, got {raw[:40]!r})", "with")
            result = await run_in_threadpool(service.compare, s.user, job_id, int(raw))
        except PortalError as exc:
            return refused(request, s, exc.message, exc.status)
        rows = [{"label": m["label"], "values": [_metric_text(run.get(m["key"]), m["key"]) for run in result["runs"]]}
                for m in result["metrics"]]
        return page(request, "compare.html", s, job=job, other=int(raw), result=result, rows=rows,
                    tracks=result["tracks"])

    @r.post("/jobs/{job_id}/cancel")
    async def cancel(request: Request, job_id: int, s: Session = Depends(signed_in)) -> Response:
        form = await checked_form(request, s)
        if isinstance(form, Response):
            return form
        try:
            await run_in_threadpool(service.cancel, s.user, job_id)
        except PortalError as exc:
            return refused(request, s, exc.message, exc.status)
        return RedirectResponse(f"/jobs/{job_id}", status_code=303)

    @r.get("/jobs/{job_id}/report")
    def report_page(request: Request, job_id: int, s: Session = Depends(signed_in)) -> Response:
        from swarmdeck.console.sandbox.report_html import render_html

        try:
            report = service.report(s.user, job_id)
        except PortalError as exc:
            return refused(request, s, exc.message, exc.status)
        return HTMLResponse(render_html(report), headers={"Content-Security-Policy": REPORT_CSP,
                                                          "Cache-Control": "no-store"})

    @r.get("/jobs/{job_id}/files/{name}")
    async def download(request: Request, job_id: int, name: str, s: Session = Depends(signed_in)) -> Response:
        try:
            path = await run_in_threadpool(service.file_path, s.user, job_id, name)  # video.mp4: made now if need be
        except PortalError as exc:
            return refused(request, s, exc.message, exc.status)
        if name == "sweep-report.html":  # a sweep's report opens here, sandboxed (sweep_job.REPORT_HEADERS)
            return FileResponse(path, filename=f"job{job_id}-{name}", content_disposition_type="inline",
                                headers=REPORT_HEADERS)
        return FileResponse(path, filename=f"job{job_id}-{name}")

    @r.get("/jobs/{job_id}/files/plots/{name}")
    async def sweep_plot(request: Request, job_id: int, name: str, s: Session = Depends(signed_in)) -> Response:
        try:
            path = await run_in_threadpool(service.file_path, s.user, job_id, f"plots/{name}")
        except PortalError as exc:
            return refused(request, s, exc.message, exc.status)
        return FileResponse(path, media_type="image/png", content_disposition_type="inline")

    @r.get("/jobs/{job_id}/live")
    async def live_stream(request: Request, job_id: int, s: Session | None = Depends(session_of)) -> Response:
        if s is None:
            return Response("not signed in", status_code=401, media_type="text/plain")
        try:
            job = service.job(s.user, job_id)
        except PortalError as exc:
            return Response(exc.message, status_code=exc.status, media_type="text/plain")
        return StreamingResponse(live_events(request, s, job_id, job.state), media_type="text/event-stream",
                                 headers={"Cache-Control": "no-store", "X-Accel-Buffering": "no"})

    shared: dict[str, Any] = {"seq": None, "text": ""}  # the newest frame event, made once for every viewer

    def frame_event(seq: int, frame: Any) -> str:
        if shared["seq"] != seq:
            shared["seq"], shared["text"] = seq, _sse("frame", scene_message(frame, seq))
        return str(shared["text"])

    async def live_events(request: Request, s: Session, job_id: int, state: str):  # noqa: ANN202 - async gen
        """The stream: ``frame`` events (scene messages of the newest Frame, looked at every LIVE_PERIOD s: the
        Frames in between are skipped), ``state`` events (``{"state", "final"}`` on change); it ends when the job
        has ended or the session has. The feed is polled without blocking, so a watcher holds no worker thread
        (the API's routes share the thread pool)."""
        seq, sent_state, checked, idle = -1, None, -math.inf, 0
        while True:
            now = time.monotonic()
            if now - checked >= CHECK_PERIOD:
                checked = now
                try:
                    await run_in_threadpool(service.accounts.session, s.id)  # signed out or disabled: stop
                except Unauthorized:
                    yield _sse("state", {"state": state, "final": True, "message": "signed out"})
                    return
                state = await run_in_threadpool(service.job_state, job_id) or state
                if state != sent_state:
                    sent_state = state
                    yield _sse("state", {"state": state, "final": state in FINAL})
                if state in FINAL:
                    return
            new, running, frame = live.latest_of(job_id)  # several arenas publish into one feed
            if new != seq and running == job_id and frame is not None:
                yield frame_event(new, frame)
                idle = 0
            elif (idle := idle + 1) * LIVE_PERIOD >= 15.0:  # a comment now and then keeps proxies from closing it
                yield ": idle\n\n"
                idle = 0
            seq = new
            await asyncio.sleep(max(0.0, LIVE_PERIOD - (time.monotonic() - now)))

    # ------------------------------------------------------------------ operators
    def operator_page(request: Request, s: Session, status: int = 200, message: str | None = None) -> HTMLResponse:
        everyone = service.jobs(s.user)
        arena = service.arena_state(s.user)
        running = arena.running
        sig = "|".join([str(arena.stopped).lower(), str(arena.manual_approval).lower(),
                        "" if running is None else str(running.id), "" if running is None else str(running.state),
                        ",".join(str(j.id) for j in arena.queue),
                        ",".join(f"{j.id}:{j.state}" for j in everyone),
                        str(len((arena.alerts or {}).get("messages", [])))])  # as refresh.js sums it up
        return page(request, "operator.html", s, status=status, message=message, arena=arena, sig=sig,
                    approve=[j for j in everyone if j.state == JobState.AWAITING_APPROVAL],
                    held=[j for j in everyone if j.state == JobState.HELD],
                    jobs=everyone[:100])

    @r.get("/operator")
    def operator(request: Request, s: Session = Depends(signed_in)) -> Response:
        if not s.user.is_operator:
            return refused(request, s, "this page is for operators", 403)
        return operator_page(request, s)

    async def operator_post(request: Request, s: Session, act: Callable[[Session, FormData], object]) -> Response:
        form = await checked_form(request, s)
        if isinstance(form, Response):
            return form
        try:
            await run_in_threadpool(act, s, form)
        except PortalError as exc:
            return operator_page(request, s, exc.status, exc.message)
        return RedirectResponse("/operator", status_code=303)

    @r.post("/operator/jobs/{job_id}/{action}")
    async def operator_action(request: Request, job_id: int, action: str, s: Session = Depends(signed_in)) -> Response:
        def act(s: Session, form: FormData) -> None:
            u = s.user
            simple = {"approve": service.approve, "hold": service.hold, "release": service.release,
                      "cancel": service.operator_cancel}
            if action in simple:
                simple[action](u, job_id)
            elif action in ("bypass-approve", "bypass-refuse"):
                service.decide_bypass(u, job_id, action == "bypass-approve")
            elif action in ("forbid-barrier", "allow-barrier"):
                service.forbid_barrier(u, job_id, action == "forbid-barrier")
            elif action in ("up", "down", "top"):
                position = service.job(u, job_id).position
                if position is None:
                    raise BadInput(f"job {job_id} is not in the arena queue", "job")
                service.move(u, job_id, {"up": max(0, position - 1), "down": position + 1, "top": 0}[action])
            else:
                raise BadInput(f"unknown action {action[:40]!r}", "action")

        return await operator_post(request, s, act)

    @r.post("/operator/estop")
    async def estop(request: Request, s: Session = Depends(signed_in)) -> Response:
        return await operator_post(request, s, lambda s, form: service.emergency_stop(s.user))

    @r.post("/operator/release")
    async def release(request: Request, s: Session = Depends(signed_in)) -> Response:
        return await operator_post(request, s, lambda s, form: service.release_arena(s.user))

    @r.post("/operator/arenas/{name}/estop")
    async def arena_estop(request: Request, name: str, s: Session = Depends(signed_in)) -> Response:
        return await operator_post(request, s, lambda s, form: service.emergency_stop(s.user, name))

    @r.post("/operator/arenas/{name}/release")
    async def arena_release(request: Request, name: str, s: Session = Depends(signed_in)) -> Response:
        return await operator_post(request, s, lambda s, form: service.release_arena(s.user, name))

    @r.post("/operator/arenas/{name}/regions/{region}/estop")
    async def region_estop(request: Request, name: str, region: str, s: Session = Depends(signed_in)) -> Response:
        return await operator_post(request, s, lambda s, form: service.emergency_stop_region(s.user, name, region))

    @r.post("/operator/arenas/{name}/regions/{region}/release")
    async def region_release(request: Request, name: str, region: str, s: Session = Depends(signed_in)) -> Response:
        return await operator_post(request, s, lambda s, form: service.release_region(s.user, name, region))

    @r.post("/operator/approval")
    async def approval(request: Request, s: Session = Depends(signed_in)) -> Response:
        def act(s: Session, form: FormData) -> None:
            value = form.get("manual")
            if value not in ("on", "off"):
                raise BadInput("manual approval is 'on' or 'off'", "manual")
            service.set_manual_approval(s.user, value == "on")

        return await operator_post(request, s, act)

    @r.get("/operator/audit")
    def audit(request: Request, s: Session = Depends(signed_in)) -> Response:
        try:
            entries = service.audit_log(s.user, 500)
        except PortalError as exc:
            return refused(request, s, exc.message, exc.status)
        return page(request, "audit.html", s, entries=entries)

    # ------------------------------------------------------------------ static files
    @r.get("/static/{name}")
    def static(name: str) -> Response:
        if name not in STATIC:
            return Response("not found", status_code=404, media_type="text/plain")
        return FileResponse(HERE / "static" / name, media_type=STATIC[name],
                            headers={"Cache-Control": "no-cache", "X-Content-Type-Options": "nosniff"})

    return r


def _metric_text(value: Any, key: str) -> str:
    """A metric as the comparison table shows it ("–" where undefined)."""
    if value is None:
        return "–"
    if key == "bounds" or isinstance(value, list):
        return ", ".join(str(v) for v in value)
    if isinstance(value, float):
        return f"{value:.4g}"
    return str(value)


class SignInRequired(SwarmdeckError):
    """A page behind sign-in was asked for without a valid session: :func:`to_signin_page` answers it."""


async def to_signin_page(request: Request, exc: Exception) -> Response:
    """The answer to :class:`SignInRequired`: see other, ``/signin`` (the app's exception handler)."""
    return RedirectResponse("/signin", status_code=303)


def _sse(event: str, data: Any) -> str:
    return f"event: {event}\ndata: {json.dumps(data, separators=(',', ':'))}\n\n"


def manifest_from_form(values: dict[str, Any], filename: str | None,
                       limits: Limits) -> tuple[dict[str, Any] | None, list[PortalError]]:
    """The manifest object from the upload form's fields and every problem with them (each naming its field).

    Numbers are converted when they parse and passed on as typed otherwise (the checks then say what is
    wrong with them). Initial poses: one robot per line, ``x y θ`` (m, m, rad; commas allowed), numbered from 1
    like the lines. A .zip with every manifest field empty uses its own ``manifest.json`` (None; the entry
    field may still name the script to run).
    """
    text = {k: str(values.get(k) or "").strip() for k in ("name", "robots", "duration", "initial_poses", "params")}
    if (filename or "").lower().endswith(".zip") and not any(text.values()) and not values.get("no_barrier"):
        return None, []
    errors: list[PortalError] = []
    m: dict[str, Any] = {"name": text["name"], "robots": _number(text["robots"], int),
                         "duration": _number(text["duration"], float), "no_barrier": bool(values.get("no_barrier"))}
    if not text["name"]:
        errors.append(BadInput("give the experiment a name", "name"))
    for key, what in (("robots", "how many robots"), ("duration", "the duration in seconds")):
        if m[key] is None:
            errors.append(BadInput(f"give {what}", key))
    if text["initial_poses"]:
        try:
            m["initial_poses"] = _poses(text["initial_poses"])
        except BadInput as exc:
            errors.append(exc)
    if text["params"]:
        try:
            m["params"] = _params(text["params"])
        except BadInput as exc:
            errors.append(exc)
    entry = str(values.get("entry") or "").strip()
    if entry and not (filename or "").lower().endswith(".zip"):
        errors.append(BadInput("the entry file is only for a .zip (a .py is its own entry): leave it empty", "entry"))
    elif entry:
        m["entry"] = entry
    known = {e.field for e in errors}
    probe = {k: v for k, v in m.items() if v is not None and k not in known}
    # a field already reported is checked no further; the others are checked against stand-ins for it (the
    # poses against their own count when the robots are wrong)
    probe.setdefault("name", "x")
    probe.setdefault("duration", min(1.0, limits.max_duration))
    errors += [e for e in manifest_errors(probe, limits, first=1) if e.field not in known]  # poses: as the lines
    return m, errors


def _params(text: str) -> dict[str, Any]:
    """The Parameters field: one ``name = value`` a line (values read as ``--param`` reads them); BadInput
    (``params``) naming the line. The names and kinds are checked against the script's declaration later."""
    from swarmdeck.console.sweep.design import scalar

    out: dict[str, Any] = {}
    for k, line in enumerate(ln for ln in text.splitlines() if ln.strip()):
        name, sep, value = line.partition("=")
        name, value = name.strip(), value.strip()
        where = f"parameters, line {k + 1}: {line.strip()[:60]!r}"
        if not sep or not name.isidentifier() or not value:
            raise BadInput(f"{where} is not name = value (e.g. gain = 0.5)", "params")
        if name in out:
            raise BadInput(f"{where} sets {name} a second time", "params")
        if any(c in value for c in ",") or value.count(":") >= 2:
            raise BadInput(f"{where}: one value per parameter here (a sweep of values is `swarmdeck submit "
                           "--sweep`)", "params")
        out[name] = scalar(value)
    return out


def _number(text: str, kind: type) -> Any:
    if not text:
        return None
    try:
        return kind(text)
    except ValueError:
        try:
            return float(text) if kind is int else text  # "2.5" robots: the service says it must be an integer
        except ValueError:
            return text


def _poses(text: str) -> list[list[float]]:
    rows = []
    for k, line in enumerate(ln for ln in text.splitlines() if ln.strip()):
        parts = line.replace(",", " ").split()
        try:
            row = [float(p) for p in parts]
        except ValueError:
            raise BadInput(f"initial poses, line {k + 1}: {line.strip()[:60]!r} is not three numbers x y θ",
                           "initial_poses") from None
        if len(row) != 3:
            raise BadInput(f"initial poses, line {k + 1}: give three numbers x y θ (m, m, rad), got {len(row)}",
                           "initial_poses")
        rows.append(row)
    return rows
