"""The routes remote arena runners use (``/api/runner/...``; the rules: :mod:`.remote`). Every call is
authenticated with an operator's token (``swarmdeck users add NAME --role operator``) and, after ``connect``,
carries the arena's lease. Thin, as :mod:`.api`.
"""
from __future__ import annotations

from collections.abc import Awaitable, Callable
from typing import Any

from fastapi import APIRouter, Depends, Request
from fastapi.responses import Response
from pydantic import BaseModel, Field, StrictInt

from swarmdeck.console.portal.accounts import User
from swarmdeck.console.portal.errors import BadInput
from swarmdeck.console.portal.models import JobOut, OkOut
from swarmdeck.console.portal.remote import RemoteArenas


class ConnectIn(BaseModel):
    arena: str


class LeaseIn(BaseModel):
    arena: str
    lease: str


class HeartbeatIn(LeaseIn):
    job: StrictInt | None = Field(default=None, description="the job the runner runs now")


class ClaimIn(LeaseIn):
    job: StrictInt | None = Field(default=None, description="null: which job is next; an id: claim that job")
    wait: str | None = Field(default=None, description="with job: why it cannot start yet (its robots)")


class FinishIn(LeaseIn):
    state: str = Field(description="done | failed | cancelled")
    reason: str | None = None


class AttentionIn(LeaseIn):
    message: str


class ConnectOut(BaseModel):
    lease: str
    arena: dict[str, Any]
    lease_s: float
    heartbeat_s: float
    grace_s: float
    tick_budget_s: float | None
    max_piece: int = Field(description="the largest upload piece, bytes")
    interrupted: list[int]


class HeartbeatOut(BaseModel):
    stopped: bool
    end_job: bool
    state: str | None


class ClaimOut(BaseModel):
    job: JobOut | None
    stopped: bool
    claimed: bool = False


class SizeOut(BaseModel):
    size: int


class StateOut(BaseModel):
    state: str | None


def remote_router(remote: RemoteArenas, user: Callable[[Request], Awaitable[User]], max_piece: int) -> APIRouter:
    """The ``/runner`` routes on ``remote``; ``user`` is :func:`.api.api_router`'s dependency."""
    router = APIRouter(prefix="/runner", tags=["remote runner"])

    def body(b: Any, key: str) -> Any:
        if b is None:
            raise BadInput(f"send a JSON body with {key!r}", key)
        return b

    @router.post("/connect", response_model=ConnectOut)
    def connect(b: ConnectIn | None = None, u: User = Depends(user)) -> dict[str, Any]:
        """Take an arena (409 while another runner holds it): its lease and settings."""
        return {**remote.connect(u, body(b, "arena").arena), "max_piece": max_piece}

    @router.post("/heartbeat", response_model=HeartbeatOut)
    def heartbeat(b: HeartbeatIn | None = None, u: User = Depends(user)) -> dict[str, Any]:
        b = body(b, "lease")
        return remote.heartbeat(u, b.arena, b.lease, b.job)

    @router.post("/claim", response_model=ClaimOut)
    def claim(b: ClaimIn | None = None, u: User = Depends(user)) -> dict[str, Any]:
        b = body(b, "lease")
        return remote.claim(u, b.arena, b.lease, b.job, b.wait)

    @router.get("/jobs/{job_id}/bundle", response_class=Response,
                responses={200: {"content": {"application/octet-stream": {}}, "description": "the job files (zip)"}})
    def bundle(job_id: int, arena: str, lease: str, u: User = Depends(user)) -> Response:
        return Response(remote.script(u, arena, lease, job_id), media_type="application/octet-stream")

    @router.post("/jobs/{job_id}/running", response_model=OkOut)
    def running(job_id: int, b: LeaseIn | None = None, u: User = Depends(user)) -> dict[str, Any]:
        b = body(b, "lease")
        return {"ok": remote.running(u, b.arena, b.lease, job_id)}

    @router.put("/jobs/{job_id}/files/{name}", response_model=SizeOut)
    async def upload(request: Request, job_id: int, name: str, arena: str, lease: str, offset: int = 0,
                     u: User = Depends(user)) -> dict[str, Any]:
        from starlette.concurrency import run_in_threadpool

        data = await request.body()
        return {"size": await run_in_threadpool(remote.upload, u, arena, lease, job_id, name, offset, data)}

    @router.post("/jobs/{job_id}/finish", response_model=StateOut)
    def finish(job_id: int, b: FinishIn | None = None, u: User = Depends(user)) -> dict[str, Any]:
        b = body(b, "state")
        return {"state": remote.finish(u, b.arena, b.lease, job_id, b.state, b.reason)}

    @router.post("/attention", response_model=OkOut)
    def attention(b: AttentionIn | None = None, u: User = Depends(user)) -> dict[str, Any]:
        b = body(b, "message")
        remote.attention(u, b.arena, b.lease, b.message)
        return {"ok": True}

    return router
