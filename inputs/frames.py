"""What decoders hand to the contact table: one committed frame of a source.

Decoders (TUIO 1.1, TUIO 2.0, OSC point streams) turn parsed OSC messages into
:class:`SourceFrame` objects holding *normalised surface* entities; the contact
table calibrates them into arena metres. An entity is a plain tuple (cheap to
build at 10 000 bundles/s) indexed by the constants below.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

#: Entity tuple layout: ``(x, y, vx, vy, area, pressure, kind, class_id)``.
#: ``x, y``: normalised 0..1, origin top-left, y down. ``vx, vy``: axis lengths/s,
#: ``nan`` when the sender gives none. ``area``: normalised area or ``nan``.
#: ``pressure``: 0..1 or ``nan``. ``kind``: str. ``class_id``: int or ``None``.
X, Y, VX, VY, AREA, PRESS, KIND, CLS = range(8)

NAN = float("nan")


@dataclass(frozen=True, slots=True)
class SourceFrame:
    """One committed update of one source.

    Attributes:
        source: the source name (contact table and health key).
        kind: ``"tuio"``, ``"tuio2"`` or ``"points"``.
        points: session id → entity tuple.
        complete: ``True`` when ``points`` is the full set (TUIO ALIVE semantics:
            ids not listed are gone); ``False`` for partial updates (point streams).
        restart: the sender restarted: end every current contact first.
        presence_timeout: s; for partial sources, a point not updated for this
            long is removed (``None``: never, rely on ``complete`` frames).
    """

    source: str
    kind: str
    points: dict
    complete: bool = True
    restart: bool = False
    presence_timeout: float | None = None


class Problems(Protocol):
    """Where decoders count bad input and quirks (``n`` at once), per source name."""

    def error(self, name: str, kind: str, reason: str, detail: str, n: int = 1) -> None: ...

    def warn(self, name: str, kind: str, reason: str, n: int = 1) -> None: ...
