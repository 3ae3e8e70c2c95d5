"""The JSON routes of several arenas behind one portal (issue 30), included in :func:`.api.api_router`:

* ``GET /api/arenas``: every arena, its kind, robots, whether it is stopped or connected, its jobs now;
* ``POST /api/operator/arenas/{name}/estop`` and ``/release``: one arena's emergency stop;
* ``POST /api/operator/arenas/{name}/regions/{region}/estop`` and ``/release``: one region's (a divided floor);
* ``GET /api/reservations``; ``POST /api/operator/reservations`` (book an arena for a researcher or a group);
  ``DELETE /api/operator/reservations/{id}``;
* ``PUT /api/operator/users/{name}/group``: a researcher's group (reservations for a group cover its members);
* ``GET``/``PUT /api/me/notifications``: your webhook and e-mail address, and your latest notifications.

Thin, as :mod:`.api`: authenticate, call one service method, return its JSON under a response model.
"""
from __future__ import annotations

from collections.abc import Awaitable, Callable
from typing import Any

from fastapi import APIRouter, Depends, Request

from swarmdeck.console.portal.accounts import User
from swarmdeck.console.portal.errors import BadInput
from swarmdeck.console.portal.models import (
    ArenaInfoOut,
    ArenaOut,
    GroupIn,
    GroupOut,
    NotifyIn,
    NotifyOut,
    OkOut,
    RegionsOut,
    ReservationIn,
    ReservationOut,
)
from swarmdeck.console.portal.service import PortalService


def lab_router(service: PortalService, user: Callable[[Request], Awaitable[User]]) -> APIRouter:
    """The routes of the module docstring on ``service``; ``user`` is :func:`.api.api_router`'s dependency."""
    router = APIRouter()

    @router.get("/arenas", tags=["arenas"], response_model=list[ArenaInfoOut])
    def arenas(u: User = Depends(user)) -> list[dict[str, Any]]:
        """Every arena behind the portal and how it is now."""
        return service.arenas_state()

    @router.post("/operator/arenas/{name}/estop", tags=["operator"], response_model=ArenaOut)
    def arena_estop(name: str, u: User = Depends(user)) -> dict[str, Any]:
        """Emergency stop of one arena: its robots stop now, its jobs end, it takes no job until released."""
        return service.emergency_stop(u, name).to_dict()

    @router.post("/operator/arenas/{name}/release", tags=["operator"], response_model=ArenaOut)
    def arena_release(name: str, u: User = Depends(user)) -> dict[str, Any]:
        return service.release_arena(u, name).to_dict()

    @router.post("/operator/arenas/{name}/regions/{region}/estop", tags=["operator"], response_model=RegionsOut)
    def region_estop(name: str, region: str, u: User = Depends(user)) -> dict[str, Any]:
        """Emergency stop of one region of a divided floor: its robots stop now (the other regions run on), its job
        ends, it takes no job until released."""
        return service.emergency_stop_region(u, name, region)

    @router.post("/operator/arenas/{name}/regions/{region}/release", tags=["operator"], response_model=RegionsOut)
    def region_release(name: str, region: str, u: User = Depends(user)) -> dict[str, Any]:
        """Release one region: its robots return to their parking places, it takes the next job."""
        return service.release_region(u, name, region)

    @router.get("/reservations", tags=["arenas"], response_model=list[ReservationOut])
    def reservations(u: User = Depends(user)) -> list[dict[str, Any]]:
        """The reservations that have not ended (the queue plans around them)."""
        return [r.to_dict() for r in service.reservations(u)]

    @router.post("/operator/reservations", status_code=201, tags=["operator"], response_model=ReservationOut)
    def reserve(body: ReservationIn | None = None, u: User = Depends(user)) -> dict[str, Any]:
        """Book an arena for a researcher or a group over [start, end): only their jobs run there then. 409 when it
        overlaps another reservation of that arena; 400 when it lies in the past."""
        if body is None:
            raise BadInput("send a JSON body with arena, start, end and user or group", "arena")
        return service.reserve(u, arena=body.arena, start=body.start, end=body.end, for_user=body.user,
                               group=body.group, note=body.note).to_dict()

    @router.delete("/operator/reservations/{res_id}", tags=["operator"], response_model=OkOut)
    def unreserve(res_id: int, u: User = Depends(user)) -> dict[str, Any]:
        service.cancel_reservation(u, res_id)
        return {"ok": True}

    @router.put("/operator/users/{name}/group", tags=["operator"], response_model=GroupOut)
    def set_group(name: str, body: GroupIn | None = None, u: User = Depends(user)) -> dict[str, Any]:
        if body is None:
            raise BadInput("send a JSON body with 'group'", "group")
        return service.set_group(u, name, body.group)

    @router.get("/me/notifications", tags=["accounts"], response_model=NotifyOut)
    def notifications(u: User = Depends(user)) -> dict[str, Any]:
        return service.notification_targets(u)

    @router.put("/me/notifications", tags=["accounts"], response_model=NotifyOut)
    def set_notifications(body: NotifyIn | None = None, u: User = Depends(user)) -> dict[str, Any]:
        """Where you are told when your jobs are verified, start, end or are rejected (null: nowhere)."""
        if body is None:
            raise BadInput("send a JSON body with webhook and/or email", "webhook")
        return service.set_notification_targets(u, body.webhook, body.email)

    return router
