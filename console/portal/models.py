"""The JSON API's request and response shapes, as pydantic models: what ``/openapi.json`` (and ``/docs``) show.

Every JSON route of :mod:`.api` names its response model here, so the schema describes each response; request
bodies are validated by these models (a wrong or missing field is 422 naming it, :mod:`.app`). The service
returns typed objects (:class:`~.job.Job`, :class:`~.service.ArenaState`, :class:`~.jobfiles.ResultFile`) or
plain dicts; the routes hand those to FastAPI, which checks them against the model.

Nested documents the portal passes on as written elsewhere (the verification report, a run's barrier
statistics, the fleet table) are models that keep every key (``extra="allow"``) and name the keys a client can
rely on.
"""
from __future__ import annotations

from typing import Any

from pydantic import BaseModel, ConfigDict, Field, StrictBool, StrictInt

from swarmdeck.console.portal.job import BypassDecision, ExportState
from swarmdeck.console.portal.states import JobState


class _Open(BaseModel):
    """A document that keeps keys beyond those named."""

    model_config = ConfigDict(extra="allow")


# ---------------------------------------------------------------------- requests
class MoveIn(BaseModel):
    """``POST /api/operator/jobs/{id}/move``."""

    position: StrictInt = Field(ge=0, description="0-based place in the arena queue (0: next)")


class BarrierIn(BaseModel):
    """``POST /api/operator/jobs/{id}/barrier``."""

    forbid: StrictBool = Field(description="true: the job always runs with the barrier; false: allow its bypass")


class BypassIn(BaseModel):
    """``POST /api/operator/jobs/{id}/bypass``."""

    approve: StrictBool = Field(description="true: run without the barrier, with the guard; false: with the barrier")


class SettingsIn(BaseModel):
    """``PUT /api/operator/settings``."""

    manual_approval: StrictBool = Field(description="true: an operator approves each verified job")


class TokenIn(BaseModel):
    """``POST /api/session``."""

    token: str = Field(description="an access token (``swarmdeck users add``)")


# ---------------------------------------------------------------------- responses
class OkOut(BaseModel):
    ok: bool


class UserOut(BaseModel):
    id: int
    name: str
    role: str = Field(description="researcher | operator")
    disabled: bool


class LimitUse(BaseModel):
    used: int | float
    limit: int | float | None = Field(description="null: no limit")


class MeOut(UserOut):
    """Who a token or session belongs to; ``csrf`` only when signed in by cookie."""

    limits: dict[str, LimitUse] = Field(
        description="unfinished_jobs, verify_cpu_s_today (CPU s), results_bytes: each {used, limit}")
    csrf: str | None = Field(default=None, description="the session's CSRF token (send it as X-CSRF-Token)")


class SessionOut(BaseModel):
    user: UserOut
    csrf: str
    expires: float = Field(description="UNIX s")


class PackageOut(BaseModel):
    name: str
    version: str | None


class EnvOut(BaseModel):
    """What scripts can import (:func:`swarmdeck.console.sandbox.script_env.listing`)."""

    script_env: str | None
    python: str
    packages: list[PackageOut]
    provided: list[PackageOut]
    always: list[str]
    request: str


class JobOut(BaseModel):
    """A job (:class:`~swarmdeck.console.portal.job.Job`). Times are UNIX s (null: not yet)."""

    id: int
    name: str
    owner: str
    state: JobState
    held_from: JobState | None = Field(description="the state a held job goes back to")
    kind: str = Field(description="py | zip")
    script: str = Field(description="the uploaded file's name")
    entry: str = Field(description="what runs: script.py, or the .py inside the .zip")
    robots: int
    duration: float = Field(description="declared run length, s")
    initial_poses: list[list[float]] | None = Field(description="[x m, y m, θ rad] per robot; null: the default start")
    request_no_barrier: bool
    barrier_forbidden: bool
    verdict: str | None
    safety_score: float | None
    bypass: bool | None = Field(description="the run went without the barrier (set when it starts)")
    reason: str | None
    bypass_decision: BypassDecision | None
    bypass_pending: bool = Field(description="waiting for an operator's decision on running without the barrier")
    position: int | None = Field(description="0-based place in the arena queue; null when not in it")
    created: float
    updated: float
    started: float | None
    ended: float | None
    exports: ExportState | None = Field(description="the CSV, replay and video: writing | ready | failed")
    results_deleted: float | None = Field(description="when the retention sweep deleted the files")
    arena: str | None = Field(default=None, description="the arena the manifest asked for; null: any")
    needs: str = Field(default="either", description="either | physical | simulated robots")
    placed: str | None = Field(default=None, description="the arena the job was placed on when it started")
    eta_start: float | None = Field(default=None, description="estimated start, UNIX s (null: not planned)")
    eta_end: float | None = Field(default=None, description="estimated end (after the robots' return), UNIX s")
    eta_arena: str | None = Field(default=None, description="the arena the plan puts the waiting job on")
    sweep: dict[str, Any] | None = Field(default=None, description="a sweep job's request (params, seeds, robots, "
                                         "design, samples, duration); null: an arena job")
    params: dict[str, Any] | None = Field(default=None, description="the script's parameter values "
                                          "(swarmdeck.devices.params); null: its defaults")
    origin: int | None = Field(default=None, description="the sweep job whose best point this job runs "
                                                          "(null: submitted directly)")


class ReportOut(_Open):
    """The verification report (schema ``swarmdeck.verification/1``; its config and per-script runs kept whole)."""

    model_config = ConfigDict(extra="allow", populate_by_name=True)

    schema_: str | None = Field(default=None, alias="schema")
    verdict: str | None = None
    safety_score: float | None = None
    reasons: list[str] = Field(default_factory=list)
    config: dict[str, Any] | None = None
    scripts: list[dict[str, Any]] = Field(default_factory=list)


class ManeuverOut(BaseModel):
    ok: bool | None
    collisions: int | None
    seconds: float | None


class ContactsOut(BaseModel):
    count: int
    robots: list[int]


class ResultsOut(BaseModel):
    """An ended job in short (:func:`~swarmdeck.console.portal.results.results_summary`)."""

    model_config = ConfigDict(populate_by_name=True)

    job: int
    state: JobState
    ended_by: str | None
    barrier: dict[str, Any] | None = Field(description="ticks, stepped_in_ticks, robots, min_distance_m")
    bypass: dict[str, Any] | None = Field(description="granted, revoked {t, why}")
    contacts: ContactsOut | None
    setup: ManeuverOut | None
    return_: ManeuverOut | None = Field(alias="return")
    files: list[str]
    exports: ExportState | None
    command: str = Field(description="the command that downloads the files")
    sweep: dict[str, Any] | None = Field(default=None, description="a sweep job's results: runs, failed, the "
                                         "summary table (rows of summary.csv) and the report's file name")


class LogOut(BaseModel):
    text: str
    next: int = Field(description="the byte to ask for next (since=next)")
    live: bool = Field(description="the job is on the arena: more may come")


class FileOut(BaseModel):
    name: str
    bytes: int | None
    what: str


class SettingsOut(BaseModel):
    manual_approval: bool


class AlertsOut(BaseModel):
    job: int | None
    messages: list[str]


class RegionOut(BaseModel):
    """One region of a floor divided into regions (``--arena NAME=sim,regions=2x2``)."""

    name: str
    robots: int = Field(description="robots a job there may use")
    stopped: bool = Field(description="emergency-stopped by an operator (until released)")
    job: int | None = Field(description="the job running there now")


class RegionsOut(BaseModel):
    """The regions of one arena (``POST /api/operator/arenas/{name}/regions/{region}/estop``)."""

    arena: str
    regions: list[RegionOut]


class ArenaInfoOut(BaseModel):
    """One arena behind the portal (``swarmdeck server --arena NAME=SPEC``) and how it is now."""

    name: str
    kind: str = Field(description="physical | simulated")
    robots: int
    remote: bool = Field(description="its runner is another process (swarmdeck runner)")
    slots: int = Field(description="jobs it runs at once")
    fast: bool
    stopped: bool = Field(description="emergency-stopped (its own latch or the whole portal's)")
    connected: bool = Field(description="can take jobs now (a remote runner was heard from lately)")
    running: list[int] = Field(description="the ids of the jobs on it now")
    fleet: dict[str, Any] | None = Field(default=None, description="its fleet table (in-process arenas)")
    regions: list[RegionOut] | None = Field(default=None, description="its regions (a floor divided into regions)")


class ReservationIn(BaseModel):
    """``POST /api/operator/reservations``: book an arena for a researcher or a group."""

    arena: str
    start: float = Field(description="UNIX s")
    end: float = Field(description="UNIX s, after start and after now")
    user: str | None = Field(default=None, description="the researcher it is for (or group)")
    group: str | None = Field(default=None, description="the group it is for (or user)")
    note: str = ""


class ReservationOut(BaseModel):
    id: int
    arena: str
    user: str | None
    group: str | None
    start: float
    end: float
    note: str
    created_by: str | None


class GroupIn(BaseModel):
    """``PUT /api/operator/users/{name}/group``."""

    group: str | None = Field(description="the group's name; null: none")


class GroupOut(BaseModel):
    user: str
    group: str | None


class NotifyIn(BaseModel):
    """``PUT /api/me/notifications``: where you are told when your jobs are verified, start, end or are rejected."""

    webhook: str | None = Field(default=None, description="http(s) URL the portal POSTs each event to (JSON)")
    email: str | None = Field(default=None, description="address (sent through the lab's SMTP server)")


class NotifyOut(BaseModel):
    webhook: str | None
    email: str | None
    email_configured: bool = Field(description="the lab configured an SMTP server (else no e-mail is sent)")
    sent: list[dict[str, Any]] = Field(description="your latest notifications: event, channel, attempts, sent, error")


class ArenaOut(BaseModel):
    """The arena as operators see it (:class:`~swarmdeck.console.portal.service.ArenaState`)."""

    stopped: bool
    needs_operator: str | None
    alerts: AlertsOut | None
    manual_approval: bool
    running: JobOut | None
    queue: list[JobOut]
    fleet: dict[str, Any] | None = Field(description="the fleet table (robots, charge, slots); null without a fleet")
    arenas: list[ArenaInfoOut] = Field(default_factory=list, description="every arena behind the portal")


class AuditOut(BaseModel):
    id: int
    t: float
    user: str | None
    action: str
    job: int | None
    detail: str


class RejectionsOut(BaseModel):
    total: int
    by_status: dict[str, int]
    by_field: dict[str, int]


class StatsOut(BaseModel):
    rejected: RejectionsOut


class RunMetricsOut(_Open):
    """One job's run in a comparison (:class:`~swarmdeck.console.recording.metrics.RunMetrics`)."""

    name: str = Field(description="job N")
    file: str
    duration_s: float
    frames: int
    robots: int
    bounds: list[float] = Field(description="x_min, x_max, y_min, y_max (m)")
    contacts: int
    min_distance_m: float | None
    interventions: int
    coverage_cost_final: float | None
    distance_m: float


class MetricRowOut(BaseModel):
    key: str
    label: str


class TracksOut(BaseModel):
    """A run's robot poses sampled every ``period`` s (:mod:`~swarmdeck.console.recording.tracks`)."""

    name: str
    period: float
    t: list[float]
    ids: list[int]
    bounds: list[float]
    poses: list[list[list[float]]] = Field(description="(T, N, 3): x, y (m), θ (rad)")


class CompareOut(BaseModel):
    """Two jobs compared: the metric table (``runs`` × ``metrics``), what differs, both runs' tracks."""

    runs: list[RunMetricsOut]
    differences: list[str]
    metrics: list[MetricRowOut]
    tracks: list[TracksOut]
