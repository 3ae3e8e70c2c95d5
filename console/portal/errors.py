"""The portal's errors: each is an HTTP status, a one-line message and the field it is about.

The service raises them; the HTTP layer turns every one into
``{"error": message, "field": field}`` with its status and counts it
(:class:`RejectionCounter`). ``field`` names the manifest key, form field,
header or path parameter that was wrong (None when no single field is).
"""
from __future__ import annotations

import threading
from collections import Counter

from swarmdeck.core.errors import SwarmdeckError


class PortalError(SwarmdeckError):
    status = 400

    def __init__(self, message: str, field: str | None = None) -> None:
        super().__init__(message)
        self.message, self.field = message, field

    def to_dict(self) -> dict:
        return {"error": self.message, "field": self.field}


class BadInput(PortalError):
    """A request or manifest value that cannot be used (422)."""

    status = 422


class Unauthorized(PortalError):
    """No valid token or session (401)."""

    status = 401


class Forbidden(PortalError):
    """Signed in, but the role does not allow it (403)."""

    status = 403


class NotFound(PortalError):
    """No such thing — or another user's job (404: its existence is not revealed)."""

    status = 404


class Conflict(PortalError):
    """The job (or name) is not in a state that allows it: e.g. two operators acting at once (409)."""

    status = 409


class RequestTimeout(PortalError):
    """A request's body did not arrive in time (408)."""

    status = 408


class TooLarge(PortalError):
    """An upload or archive member over the configured limits (413)."""

    status = 413


class Unsupported(PortalError):
    """An upload of a type the portal does not take (415)."""

    status = 415


class RateLimited(PortalError):
    """Too many: failed sign-ins, unfinished jobs, verification CPU a day (429)."""

    status = 429


class QuotaExceeded(PortalError):
    """A researcher's quota (results on disk) is used up (403)."""

    status = 403


class Unavailable(PortalError):
    """The arena or a worker cannot take it now (503)."""

    status = 503


class RejectionCounter:
    """Thread-safe counts of rejected requests by status and by ``status field`` (for ``/api/operator/stats``)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._by_status: Counter[int] = Counter()
        self._by_field: Counter[str] = Counter()

    def count(self, status: int, field: str | None) -> None:
        with self._lock:
            self._by_status[int(status)] += 1
            self._by_field[f"{int(status)} {field or '-'}"] += 1

    def snapshot(self) -> dict:
        with self._lock:
            return {"total": sum(self._by_status.values()),
                    "by_status": {str(k): v for k, v in sorted(self._by_status.items())},
                    "by_field": dict(sorted(self._by_field.items()))}
