"""The JSON API under ``/api``: thin routes over :class:`~.service.PortalService`.

Authentication (:func:`authenticate`): ``Authorization: Bearer TOKEN``, or the
web session cookie ``swarmdeck_session`` (set by ``POST /api/session``;
HttpOnly, SameSite=Strict) — cookie-authenticated requests that change
anything must also send the session's CSRF token as ``X-CSRF-Token``.
Every request looks the token or session up again, so a disabled account is
refused from its next request on.

A revoked or expired token is 401 saying which (``swarmdeck users revoke``,
``--expires``). A submission over a researcher's limit is 429 (unfinished jobs,
verification CPU a day) or 403 (disk quota), the ``field`` naming the limit
(:mod:`.quotas`); a slow body is 408 (:mod:`.app`).

Errors: every one is a 4xx with ``{"error": message, "field": name}``
(:mod:`.errors`), counted in the app's :class:`~.errors.RejectionCounter`
(``GET /api/operator/stats``).

Routes (researchers see only their own jobs; other ids are 404):

* ``GET /api/health`` (no auth) · ``GET /api/me`` · ``POST/DELETE /api/session``
* ``GET /api/env``: what scripts can import (the lab's script environment, ``swarmdeck env``)
* ``POST /api/jobs`` (multipart: file ``script`` (.py/.zip), field ``manifest`` (JSON), field ``entry`` (the
  script inside a .zip)) → 201 job (its ``state``: :class:`~.states.JobState`; ``position`` in the arena queue
  0-based here, 1-based on the pages and in ``swarmdeck jobs``)
* ``GET /api/jobs`` · ``GET /api/jobs/{id}`` · ``POST /api/jobs/{id}/cancel``
* ``GET /api/jobs/{id}/report`` · ``GET /api/jobs/{id}/files`` · ``GET /api/jobs/{id}/files/{name}``
* ``GET /api/jobs/{id}/results`` (an ended job in short) · ``GET /api/jobs/{id}/log?since=B`` (the script's output,
  live while it runs)
* operators: ``POST /api/operator/jobs/{id}/{approve|hold|release|cancel}``,
  ``POST /api/operator/jobs/{id}/move`` ``{"position": k}``,
  ``POST /api/operator/jobs/{id}/barrier`` ``{"forbid": bool}``,
  ``POST /api/operator/jobs/{id}/bypass`` ``{"approve": bool}`` (a job's barrier bypass: approve, or refuse → it runs
  with the barrier),
  ``GET/PUT /api/operator/settings`` ``{"manual_approval": bool}``,
  ``GET /api/operator/arena``, ``POST /api/operator/estop``, ``POST /api/operator/release``,
  ``GET /api/operator/audit``, ``GET /api/operator/stats``.
"""
from __future__ import annotations

import hmac
from typing import Any

from fastapi import APIRouter, Body, Depends, Request, Response
from fastapi.responses import FileResponse
from starlette.concurrency import run_in_threadpool
from starlette.datastructures import UploadFile

from swarmdeck.console.portal.accounts import User
from swarmdeck.console.portal.errors import BadInput, Forbidden, RejectionCounter, Unauthorized
from swarmdeck.console.portal.service import PortalService

SESSION_COOKIE = "swarmdeck_session"
CSRF_HEADER = "x-csrf-token"
SAFE_METHODS = ("GET", "HEAD", "OPTIONS")

UPLOAD_SCHEMA = {
    "requestBody": {
        "required": True,
        "content": {"multipart/form-data": {"schema": {
            "type": "object", "required": ["script"],
            "properties": {
                "script": {"type": "string", "format": "binary", "description": "the script (.py) or a .zip"},
                "manifest": {"type": "string", "description": 'JSON: {"name", "robots", "duration", '
                             '"initial_poses"?, "no_barrier"?, "entry"?} (optional for a .zip with manifest.json)'},
                "entry": {"type": "string", "description": "for a .zip: the .py file inside it to run "
                          "(overrides the manifest's entry)"},
            }}}},
    }
}


def authenticate(service: PortalService, request: Request) -> User:
    """The user of a request (Bearer token, or session cookie + CSRF header for changes); Unauthorized/Forbidden."""
    header = request.headers.get("authorization")
    if header is not None:
        scheme, _, token = header.partition(" ")
        if scheme.lower() != "bearer" or not token.strip():
            raise Unauthorized("use the header 'Authorization: Bearer TOKEN'", "Authorization")
        return service.accounts.user_for_token(token.strip())
    sid = request.cookies.get(SESSION_COOKIE)
    if sid:
        session = service.accounts.session(sid)
        if request.method not in SAFE_METHODS and not hmac.compare_digest(
                request.headers.get(CSRF_HEADER, "").encode(), session.csrf.encode()):
            raise Forbidden("missing or wrong X-CSRF-Token header for a signed-in change", "X-CSRF-Token")
        return session.user
    raise Unauthorized("not signed in: send 'Authorization: Bearer TOKEN'", "Authorization")


def api_router(service: PortalService, counter: RejectionCounter, *, max_upload_bytes: int) -> APIRouter:
    """The ``/api`` routes on ``service``."""
    router = APIRouter(prefix="/api")

    async def user(request: Request) -> User:
        # On the event loop, not the thread pool: one indexed SQLite read (WAL readers never wait for a
        # writer), cheaper than the hand-off to a worker thread that a plain `def` dependency costs.
        return authenticate(service, request)

    @router.get("/health", tags=["service"])
    async def health() -> dict[str, Any]:
        """Liveness (no authentication)."""
        return {"ok": True}

    @router.get("/me", tags=["accounts"])
    def me(request: Request, u: User = Depends(user)) -> dict[str, Any]:
        """Who the token or session belongs to (with the session's CSRF token when signed in by cookie), and
        ``limits``: for each per-researcher limit, ``{"used", "limit"}`` (limit null: none)."""
        out = u.to_dict()
        out["limits"] = service.usage(u)
        sid = request.cookies.get(SESSION_COOKIE)
        if sid and "authorization" not in request.headers:
            out["csrf"] = service.accounts.session(sid).csrf
        return out

    @router.get("/env", tags=["jobs"])
    def environment(u: User = Depends(user)) -> dict[str, Any]:
        """What scripts can import: the standard library, ``always`` (swarmdeck, rps), ``provided`` (swarmdeck's own
        numpy) and ``packages`` (the lab's script environment, name and version; with ``script_env`` null, swarmdeck's
        whole environment). ``request``: how to ask for a package that is missing."""
        return service.environment()

    @router.post("/session", tags=["accounts"])
    def sign_in(request: Request, response: Response, token: str = Body(..., embed=True)) -> dict[str, Any]:
        """Sign in with an access token: sets the HttpOnly, SameSite=Strict session cookie; returns the CSRF token."""
        client = request.client.host if request.client else "?"
        session = service.accounts.sign_in(token, client)
        response.set_cookie(SESSION_COOKIE, session.id, max_age=int(service.accounts.session_s), httponly=True,
                            samesite="strict", secure=request.url.scheme == "https", path="/")
        return {"user": session.user.to_dict(), "csrf": session.csrf, "expires": session.expires}

    @router.delete("/session", tags=["accounts"])
    def sign_out(request: Request, response: Response) -> dict[str, Any]:
        sid = request.cookies.get(SESSION_COOKIE)
        if sid:
            service.accounts.sign_out(sid)
        response.delete_cookie(SESSION_COOKIE, path="/")
        return {"ok": True}

    @router.post("/jobs", status_code=201, tags=["jobs"], openapi_extra=UPLOAD_SCHEMA)
    async def submit(request: Request, u: User = Depends(user)) -> dict[str, Any]:
        """Submit a script (multipart file ``script``) with its ``manifest`` (JSON text): the new job, ``awaiting verification``."""
        form = await request.form(max_files=1, max_fields=5, max_part_size=max_upload_bytes)
        try:
            script, manifest, entry = form.get("script"), form.get("manifest"), form.get("entry")
            if not isinstance(script, UploadFile):
                raise BadInput("send the script as the multipart file field 'script'", "script")
            if manifest is not None and not isinstance(manifest, str):
                raise BadInput("the manifest is a form field holding JSON text, not a file", "manifest")
            if entry is not None and not isinstance(entry, str):
                raise BadInput("entry is a form field naming the .py file inside the .zip, not a file", "entry")
            data = await script.read(max_upload_bytes + 1)
            return await run_in_threadpool(service.submit, u, script.filename, data, manifest, entry)
        finally:
            await form.close()

    @router.get("/jobs", tags=["jobs"])
    def jobs(mine: bool = False, u: User = Depends(user)) -> list[dict[str, Any]]:
        """Your jobs, newest first (operators: everyone's, unless ``mine``)."""
        return service.jobs(u, mine=mine)

    @router.get("/jobs/{job_id}", tags=["jobs"])
    async def job(job_id: int, u: User = Depends(user)) -> dict[str, Any]:
        return service.job(u, job_id)

    @router.post("/jobs/{job_id}/cancel", tags=["jobs"])
    def cancel(job_id: int, u: User = Depends(user)) -> dict[str, Any]:
        return service.cancel(u, job_id)

    @router.get("/jobs/{job_id}/report", tags=["jobs"])
    def report(job_id: int, u: User = Depends(user)) -> dict[str, Any]:
        """The verification report (schema swarmdeck.verification/1)."""
        return service.report(u, job_id)

    @router.get("/jobs/{job_id}/results", tags=["results"])
    def results(job_id: int, u: User = Depends(user)) -> dict[str, Any]:
        """An ended job's results in short: did the barrier step in (how often, which robots), the minimum
        distance between robots, contacts, the files and the command that downloads them."""
        return service.results(u, job_id)

    @router.get("/jobs/{job_id}/log", tags=["results"])
    def script_log(job_id: int, since: int = 0, u: User = Depends(user)) -> dict[str, Any]:
        """The script's output from byte ``since``: ``{"text", "next", "live"}`` (live while the job runs; poll
        with ``since=next``). The job's owner and operators only."""
        return service.script_log(u, job_id, since)

    @router.get("/jobs/{job_id}/files", tags=["results"])
    def files(job_id: int, u: User = Depends(user)) -> list[dict[str, Any]]:
        """The job's result files: recording, CSV, HTML replay, script log, reports."""
        return service.files(u, job_id)

    @router.get("/jobs/{job_id}/files/{name}", tags=["results"])
    def download(job_id: int, name: str, u: User = Depends(user)) -> FileResponse:
        path = service.file_path(u, job_id, name)
        return FileResponse(path, filename=f"job{job_id}-{name}")

    # ------------------------------------------------------------------ operators
    @router.post("/operator/jobs/{job_id}/{action}", tags=["operator"])
    def operator_action(job_id: int, action: str, u: User = Depends(user),
                        body: dict[str, Any] | None = Body(default=None)) -> dict[str, Any]:
        """``approve``, ``hold``, ``release``, ``cancel``; ``move`` with ``{"position": k}``; ``barrier`` with
        ``{"forbid": bool}``; ``bypass`` with ``{"approve": bool}`` (the job's barrier bypass: approve it — the job runs
        without the barrier, with the guard — or refuse it — the job runs with the barrier). 409 when the job is not in
        a state that allows it (e.g. another operator was first)."""
        simple = {"approve": service.approve, "hold": service.hold, "release": service.release,
                  "cancel": service.operator_cancel}
        if action in simple:
            return simple[action](u, job_id)
        if action == "move":
            return service.move(u, job_id, _key(body, "position"))
        if action == "barrier":
            return service.forbid_barrier(u, job_id, _key(body, "forbid"))
        if action == "bypass":
            return service.decide_bypass(u, job_id, _key(body, "approve"))
        raise BadInput(f"unknown action {action[:40]!r}: approve, hold, release, cancel, move, barrier, bypass", "action")

    @router.get("/operator/settings", tags=["operator"])
    def get_settings(u: User = Depends(user)) -> dict[str, Any]:
        if not u.is_operator:
            raise Forbidden("this needs an operator account", "Authorization")
        return service.settings()

    @router.put("/operator/settings", tags=["operator"])
    def put_settings(body: dict[str, Any] = Body(...), u: User = Depends(user)) -> dict[str, Any]:
        """``{"manual_approval": bool}``."""
        return service.set_manual_approval(u, _key(body, "manual_approval"))

    @router.get("/operator/arena", tags=["operator"])
    def arena(u: User = Depends(user)) -> dict[str, Any]:
        return service.arena_state(u)

    @router.post("/operator/estop", tags=["operator"])
    def estop(u: User = Depends(user)) -> dict[str, Any]:
        """Emergency stop: robots stop now, the running job ends, the arena stays stopped until released."""
        return service.emergency_stop(u)

    @router.post("/operator/release", tags=["operator"])
    def release(u: User = Depends(user)) -> dict[str, Any]:
        return service.release_arena(u)

    @router.get("/operator/audit", tags=["operator"])
    def audit(limit: int = 200, u: User = Depends(user)) -> list[dict[str, Any]]:
        return service.audit_log(u, max(1, min(limit, 10000)))

    @router.get("/operator/stats", tags=["operator"])
    def stats(u: User = Depends(user)) -> dict[str, Any]:
        """Counts of rejected requests by status and field."""
        if not u.is_operator:
            raise Forbidden("this needs an operator account", "Authorization")
        return {"rejected": counter.snapshot()}

    return router


def _key(body: dict[str, Any] | None, key: str) -> Any:
    if not isinstance(body, dict) or key not in body:
        raise BadInput(f"send a JSON body with {key!r}", key)
    return body[key]
