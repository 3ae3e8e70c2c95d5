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

Every JSON route's request body and response is a pydantic model of :mod:`.models`, so ``/openapi.json``
describes them.

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
* ``POST /api/sweeps`` (a parameter sweep as one job, run in simulation: :mod:`.sweep_job`)
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
from typing import Any, TypeVar

from fastapi import APIRouter, Depends, Request, Response
from fastapi.responses import FileResponse
from starlette.concurrency import run_in_threadpool
from starlette.datastructures import UploadFile

from swarmdeck.console.portal.accounts import User
from swarmdeck.console.portal.errors import BadInput, Forbidden, RejectionCounter, Unauthorized
from swarmdeck.console.portal.lab_api import lab_router
from swarmdeck.console.portal.models import (
    ArenaOut,
    AuditOut,
    BarrierIn,
    BypassIn,
    CompareOut,
    EnvOut,
    FileOut,
    JobOut,
    LogOut,
    MeOut,
    MoveIn,
    OkOut,
    ReportOut,
    ResultsOut,
    SessionOut,
    SettingsIn,
    SettingsOut,
    StatsOut,
    TokenIn,
)
from swarmdeck.console.portal.remote import MAX_PIECE, RemoteArenas
from swarmdeck.console.portal.remote_api import remote_router
from swarmdeck.console.portal.service import PortalService
from swarmdeck.console.portal.sweep_job import REPORT_HEADERS

_Body = TypeVar("_Body")
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
                             '"initial_poses"?, "no_barrier"?, "entry"?, "arena"?, "needs"?, "params"?} '
                             '(optional for a .zip with manifest.json)'},
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
    """The ``/api`` routes on ``service``; each JSON route's response is a model of :mod:`.models`."""
    router = APIRouter(prefix="/api")

    async def user(request: Request) -> User:
        # On the event loop, not the thread pool: one indexed SQLite read (WAL readers never wait for a
        # writer), cheaper than the hand-off to a worker thread that a plain `def` dependency costs.
        return authenticate(service, request)

    def operator(u: User = Depends(user)) -> User:
        if not u.is_operator:
            raise Forbidden("this needs an operator account", "Authorization")
        return u

    @router.get("/health", tags=["service"], response_model=OkOut)
    async def health() -> dict[str, Any]:
        """Liveness (no authentication)."""
        return {"ok": True}

    @router.get("/me", tags=["accounts"], response_model=MeOut, response_model_exclude_unset=True)
    def me(request: Request, u: User = Depends(user)) -> dict[str, Any]:
        """Who the token or session belongs to (with the session's CSRF token when signed in by cookie), and
        ``limits``: for each per-researcher limit, ``{"used", "limit"}`` (limit null: none)."""
        out = u.to_dict()
        out["limits"] = service.usage(u)
        sid = request.cookies.get(SESSION_COOKIE)
        if sid and "authorization" not in request.headers:
            out["csrf"] = service.accounts.session(sid).csrf
        return out

    @router.get("/env", tags=["jobs"], response_model=EnvOut)
    def environment(u: User = Depends(user)) -> dict[str, Any]:
        """What scripts can import: the standard library, ``always`` (swarmdeck, rps), ``provided`` (swarmdeck's own
        numpy) and ``packages`` (the lab's script environment, name and version; with ``script_env`` null, swarmdeck's
        whole environment). ``request``: how to ask for a package that is missing."""
        return service.environment()

    @router.post("/session", tags=["accounts"], response_model=SessionOut)
    def sign_in(request: Request, response: Response, body: TokenIn) -> dict[str, Any]:
        """Sign in with an access token: sets the HttpOnly, SameSite=Strict session cookie; returns the CSRF token."""
        client = request.client.host if request.client else "?"
        session = service.accounts.sign_in(body.token, client)
        response.set_cookie(SESSION_COOKIE, session.id, max_age=int(service.accounts.session_s), httponly=True,
                            samesite="strict", secure=request.url.scheme == "https", path="/")
        return {"user": session.user.to_dict(), "csrf": session.csrf, "expires": session.expires}

    @router.delete("/session", tags=["accounts"], response_model=OkOut)
    def sign_out(request: Request, response: Response) -> dict[str, Any]:
        sid = request.cookies.get(SESSION_COOKIE)
        if sid:
            service.accounts.sign_out(sid)
        response.delete_cookie(SESSION_COOKIE, path="/")
        return {"ok": True}

    async def _script_upload(form: Any) -> tuple[str | None, bytes, str | None]:
        """The multipart form's script upload: (its file name, at most ``max_upload_bytes`` + 1 bytes, the ``entry``
        field); BadInput naming the field that is not what it must be."""
        script, entry = form.get("script"), form.get("entry")
        if not isinstance(script, UploadFile):
            raise BadInput("send the script as the multipart file field 'script'", "script")
        if entry is not None and not isinstance(entry, str):
            raise BadInput("entry is a form field naming the .py file inside the .zip, not a file", "entry")
        return script.filename, await script.read(max_upload_bytes + 1), entry

    @router.post("/jobs", status_code=201, tags=["jobs"], openapi_extra=UPLOAD_SCHEMA, response_model=JobOut)
    async def submit(request: Request, u: User = Depends(user)) -> dict[str, Any]:
        """Submit a script (multipart file ``script``) with its ``manifest`` (JSON text): the new job, ``awaiting verification``."""
        form = await request.form(max_files=1, max_fields=5, max_part_size=max_upload_bytes)
        try:
            filename, data, entry = await _script_upload(form)
            manifest = form.get("manifest")
            if manifest is not None and not isinstance(manifest, str):
                raise BadInput("the manifest is a form field holding JSON text, not a file", "manifest")
            job = await run_in_threadpool(service.submit, u, filename, data, manifest, entry)
            return job.to_dict()
        finally:
            await form.close()

    @router.post("/sweeps", status_code=201, tags=["jobs"], openapi_extra=UPLOAD_SCHEMA, response_model=JobOut)
    async def submit_sweep(request: Request, u: User = Depends(user)) -> dict[str, Any]:
        """Submit a parameter sweep as ONE job: the script (multipart file ``script``) and the ``sweep`` (JSON text:
        ``params`` ["NAME=VALUES", …] as ``swarmdeck sweep --param``, ``robots``, ``seeds``, ``seed``, ``design``,
        ``samples``, ``duration``, ``name``). It runs in simulation on the verification executors, never on the
        arena: ``awaiting verification`` → ``verifying`` → ``done`` | ``failed``; its results are
        ``GET /api/jobs/{id}/results`` and the files ``sweep-report.html``, ``results.csv``, ``summary.csv``."""
        form = await request.form(max_files=1, max_fields=5, max_part_size=max_upload_bytes)
        try:
            filename, data, entry = await _script_upload(form)
            sweep = form.get("sweep")
            if not isinstance(sweep, str):
                raise BadInput("send the sweep as the form field 'sweep' holding JSON text", "sweep")
            job = await run_in_threadpool(service.submit_sweep, u, filename, data, sweep, entry)
            return job.to_dict()
        finally:
            await form.close()

    @router.get("/jobs", tags=["jobs"], response_model=list[JobOut])
    def jobs(mine: bool = False, u: User = Depends(user)) -> list[dict[str, Any]]:
        """Your jobs, newest first (operators: everyone's, unless ``mine``)."""
        return [j.to_dict() for j in service.jobs(u, mine=mine)]

    @router.get("/jobs/{job_id}", tags=["jobs"], response_model=JobOut)
    async def job(job_id: int, u: User = Depends(user)) -> dict[str, Any]:
        return service.job(u, job_id).to_dict()

    @router.post("/jobs/{job_id}/cancel", tags=["jobs"], response_model=JobOut)
    def cancel(job_id: int, u: User = Depends(user)) -> dict[str, Any]:
        return service.cancel(u, job_id).to_dict()

    @router.get("/jobs/{job_id}/report", tags=["jobs"], response_model=ReportOut, response_model_exclude_unset=True)
    def report(job_id: int, u: User = Depends(user)) -> dict[str, Any]:
        """The verification report (schema swarmdeck.verification/1)."""
        return service.report(u, job_id)

    @router.get("/jobs/{job_id}/results", tags=["results"], response_model=ResultsOut)
    def results(job_id: int, u: User = Depends(user)) -> dict[str, Any]:
        """An ended job's results in short: did the barrier step in (how often, which robots), the minimum
        distance between robots, contacts, the files and the command that downloads them."""
        return service.results(u, job_id)

    @router.get("/jobs/{job_id}/compare/{other_id}", tags=["results"], response_model=CompareOut)
    def compare(job_id: int, other_id: int, u: User = Depends(user)) -> dict[str, Any]:
        """Two ended jobs compared: the metric table (duration, robots, contacts, minimum distance, barrier
        interventions, coverage cost H, distance travelled …), what differs between them and both runs' robot
        poses every 0.1 s (or coarser) for an overlaid view. Your own jobs only: another researcher's is 404."""
        return service.compare(u, job_id, other_id)

    @router.get("/jobs/{job_id}/log", tags=["results"], response_model=LogOut)
    def script_log(job_id: int, since: int = 0, u: User = Depends(user)) -> dict[str, Any]:
        """The script's output from byte ``since``: ``{"text", "next", "live"}`` (live while the job runs; poll
        with ``since=next``). The job's owner and operators only."""
        return service.script_log(u, job_id, since)

    @router.get("/jobs/{job_id}/files", tags=["results"], response_model=list[FileOut])
    def files(job_id: int, u: User = Depends(user)) -> list[dict[str, Any]]:
        """The job's result files: recording, CSV, HTML replay, script log, reports."""
        return [f.to_dict() for f in service.files(u, job_id)]

    @router.get("/jobs/{job_id}/files/{name}", tags=["results"], response_class=FileResponse,
                responses={200: {"content": {"application/octet-stream": {"schema": {"type": "string",
                                                                                     "format": "binary"}}},
                                 "description": "the file (one of the names GET /api/jobs/{id}/files lists)"}})
    def download(job_id: int, name: str, u: User = Depends(user)) -> FileResponse:
        path = service.file_path(u, job_id, name)
        # a sweep's report opens in the browser (its plots and tables are the links beside it)
        if name == "sweep-report.html":
            return FileResponse(path, filename=f"job{job_id}-{name}", content_disposition_type="inline",
                                headers=REPORT_HEADERS)
        return FileResponse(path, filename=f"job{job_id}-{name}")

    @router.get("/jobs/{job_id}/files/plots/{name}", tags=["results"], response_class=FileResponse,
                responses={200: {"content": {"application/octet-stream": {"schema": {"type": "string",
                                                                                     "format": "binary"}}},
                                 "description": "the PNG (a name sweep-report.html links)"}})
    def sweep_plot(job_id: int, name: str, u: User = Depends(user)) -> FileResponse:
        """A sweep job's plot ``plots/NAME.png`` (as its report links it)."""
        path = service.file_path(u, job_id, f"plots/{name}")
        return FileResponse(path, media_type="image/png", content_disposition_type="inline")

    # ------------------------------------------------------------------ operators
    simple = {"approve": service.approve, "hold": service.hold, "release": service.release,
              "cancel": service.operator_cancel}

    def simple_action(action: str, doc: str) -> None:
        def act(job_id: int, u: User = Depends(user)) -> dict[str, Any]:
            return simple[action](u, job_id).to_dict()

        act.__doc__ = doc
        router.add_api_route(f"/operator/jobs/{{job_id}}/{action}", act, methods=["POST"], tags=["operator"],
                             response_model=JobOut, name=f"operator_{action}")

    simple_action("approve", "Manual approval: the job goes to the arena queue (409 while its bypass waits for a "
                             "decision, or when it is not awaiting approval).")
    simple_action("hold", "Hold a job awaiting verification or approval or in the arena queue.")
    simple_action("release", "Release a held job to the state it was held in.")
    simple_action("cancel", "Cancel any job that has not ended (audited).")

    @router.post("/operator/jobs/{job_id}/move", tags=["operator"], response_model=JobOut)
    def move(job_id: int, body: MoveIn | None = None, u: User = Depends(user)) -> dict[str, Any]:
        """Put a job of the arena queue at ``position`` (0: next)."""
        return service.move(u, job_id, _required(body, "position").position).to_dict()

    @router.post("/operator/jobs/{job_id}/barrier", tags=["operator"], response_model=JobOut)
    def barrier(job_id: int, body: BarrierIn | None = None, u: User = Depends(user)) -> dict[str, Any]:
        """Forbid (``{"forbid": true}``) or allow again the job's running without the barrier; 409 once it is on
        the arena or has ended."""
        return service.forbid_barrier(u, job_id, _required(body, "forbid").forbid).to_dict()

    @router.post("/operator/jobs/{job_id}/bypass", tags=["operator"], response_model=JobOut)
    def bypass(job_id: int, body: BypassIn | None = None, u: User = Depends(user)) -> dict[str, Any]:
        """The job's barrier bypass: approve it (the job runs without the barrier, with the guard) or refuse it (the
        job runs with the barrier). 409 unless the job is awaiting approval and waiting for this decision (e.g.
        another operator was first)."""
        return service.decide_bypass(u, job_id, _required(body, "approve").approve).to_dict()

    @router.post("/operator/jobs/{job_id}/{action}", tags=["operator"], include_in_schema=False)
    def unknown_action(job_id: int, action: str, u: User = Depends(user)) -> None:
        raise BadInput(f"unknown action {action[:40]!r}: approve, hold, release, cancel, move, barrier, bypass", "action")

    @router.get("/operator/settings", tags=["operator"], response_model=SettingsOut)
    def get_settings(u: User = Depends(operator)) -> dict[str, Any]:
        return service.settings()

    @router.put("/operator/settings", tags=["operator"], response_model=SettingsOut)
    def put_settings(body: SettingsIn | None = None, u: User = Depends(user)) -> dict[str, Any]:
        """Switch manual approval; switching it off sends every job awaiting approval to the arena queue."""
        return service.set_manual_approval(u, _required(body, "manual_approval").manual_approval)

    @router.get("/operator/arena", tags=["operator"], response_model=ArenaOut)
    def arena(u: User = Depends(user)) -> dict[str, Any]:
        return service.arena_state(u).to_dict()

    @router.post("/operator/estop", tags=["operator"], response_model=ArenaOut)
    def estop(u: User = Depends(user)) -> dict[str, Any]:
        """Emergency stop: robots stop now, the running job ends, the arena stays stopped until released."""
        return service.emergency_stop(u).to_dict()

    @router.post("/operator/release", tags=["operator"], response_model=ArenaOut)
    def release(u: User = Depends(user)) -> dict[str, Any]:
        return service.release_arena(u).to_dict()

    @router.get("/operator/audit", tags=["operator"], response_model=list[AuditOut])
    def audit(limit: int = 200, u: User = Depends(user)) -> list[dict[str, Any]]:
        return service.audit_log(u, max(1, min(limit, 10000)))

    @router.get("/operator/stats", tags=["operator"], response_model=StatsOut)
    def stats(u: User = Depends(operator)) -> dict[str, Any]:
        """Counts of rejected requests by status and field."""
        return {"rejected": counter.snapshot()}

    router.include_router(lab_router(service, user))  # several arenas, reservations, notifications (issue 30)
    remote = service.remote if isinstance(service.remote, RemoteArenas) else RemoteArenas(service)
    service.remote = remote
    router.include_router(remote_router(remote, user, min(MAX_PIECE, max_upload_bytes)))  # remote runners
    return router


def _required(body: _Body | None, key: str) -> _Body:
    """The request's JSON body; 422 naming ``key`` when there is none."""
    if body is None:
        raise BadInput(f"send a JSON body with {key!r}", key)
    return body
