"""Value types shared by every input source: contacts, events, per-source health.

A *contact* is one finger, object, blob or tracked hand point on an operator's
input surface, already mapped into the arena frame (metres, origin at the arena
centre, x right, y up; DESIGN.md "Conventions"). Every source (TUIO 1.1,
TUIO 2.0, generic OSC point streams) produces the same :class:`Contact`.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np

EventKind = Literal["down", "move", "up", "lost", "source_lost"]


@dataclass(frozen=True, eq=False)
class Contact:
    """One touch point in arena coordinates.

    Attributes:
        source: name of the source that produced it, e.g.
            ``"udp://127.0.0.1:50123/TuioPad@10.0.0.2"`` (transport, peer, TUIO
            source string) or ``"udp://127.0.0.1:50123/manososc"`` for point streams.
        id: the sender's session id (TUIO) or a small id assigned per point key
            (point streams); unique within ``source`` only.
        position: (2,) arena metres.
        velocity: (2,) m/s (the sender's velocity when it sends one, otherwise a
            smoothed finite difference of positions over receive times).
        size: equivalent diameter in metres of a blob/bounds, when known.
        pressure: TUIO 2.0 pointer pressure (0..1), when known.
        kind: ``"cursor" | "object" | "blob" | "pointer" | "token" | "bounds" | "point"``.
        class_id: fiducial/class id of TUIO objects and tokens, when known.
        first_seen, last_seen: receive times (s, the listener's clock) of the first
            and the latest update.
    """

    source: str
    id: int
    position: np.ndarray
    velocity: np.ndarray
    size: float | None = None
    pressure: float | None = None
    kind: str = "cursor"
    class_id: int | None = None
    first_seen: float = 0.0
    last_seen: float = 0.0

    @property
    def key(self) -> tuple[str, int]:
        """``(source, id)``: unique among all contacts of all sources."""
        return (self.source, self.id)

    def to_dict(self) -> dict:
        """JSON-able form (lists instead of arrays)."""
        return {
            "source": self.source,
            "id": int(self.id),
            "position": [float(v) for v in self.position],
            "velocity": [float(v) for v in self.velocity],
            "size": self.size,
            "pressure": self.pressure,
            "kind": self.kind,
            "class_id": self.class_id,
            "first_seen": float(self.first_seen),
            "last_seen": float(self.last_seen),
        }


@dataclass(frozen=True)
class ContactEvent:
    """Something that happened to a contact (or a whole source) at time ``t``.

    ``kind``: ``down`` (new contact), ``move`` (position/velocity changed),
    ``up`` (the sender removed it, or a point stream stopped updating it within
    its presence timeout), ``lost`` (its source went silent for longer than the
    timeout), ``source_lost`` (once per silent source; ``id`` is ``None``).
    ``contact`` is the contact's last state (``None`` for ``source_lost``).
    """

    kind: EventKind
    source: str
    id: int | None
    t: float
    contact: Contact | None = None


@dataclass(frozen=True)
class SourceHealth:
    """Status of one source for the console's status line and the monitor.

    ``kind`` is ``"peer"`` for a transport peer (where datagram-level errors such
    as garbage bytes are counted), ``"tuio"``, ``"tuio2"`` or ``"points"``.
    ``rate_hz``: datagrams per second over the last second; ``last_seen``: receive
    time of the latest datagram (s); ``lost``: silent for longer than the timeout.
    ``errors``: rejected input by reason; ``warnings``: accepted input with a quirk
    (late or restarted frames, future timetags, clamped positions, ...).
    """

    name: str
    kind: str
    rate_hz: float
    last_seen: float
    datagrams: int
    contacts: int
    lost: bool
    errors: dict[str, int] = field(default_factory=dict)
    warnings: dict[str, int] = field(default_factory=dict)
    last_error: str | None = None

    @property
    def error_count(self) -> int:
        """Total number of rejected inputs."""
        return sum(self.errors.values())

    def to_dict(self) -> dict:
        """JSON-able form."""
        return {
            "name": self.name, "kind": self.kind, "rate_hz": self.rate_hz,
            "last_seen": self.last_seen, "datagrams": self.datagrams,
            "contacts": self.contacts, "lost": self.lost, "errors": dict(self.errors),
            "warnings": dict(self.warnings), "last_error": self.last_error,
        }


@dataclass(frozen=True)
class InputSnapshot:
    """What a poll returns: the current contacts, the events since the last poll
    and the health of every source, at time ``t``."""

    t: float
    contacts: tuple[Contact, ...]
    events: tuple[ContactEvent, ...]
    health: tuple[SourceHealth, ...]

    def positions(self) -> np.ndarray:
        """(K, 2) arena positions of the current contacts."""
        if not self.contacts:
            return np.zeros((0, 2))
        return np.array([c.position for c in self.contacts], dtype=float)


@dataclass(frozen=True)
class InputWork:
    """Lifetime work counters of one listener — deterministic measures of what
    ``feed`` and ``poll`` cost (the bounds of issue 14 §8–9 are on these).

    ``datagrams``: fed; ``arguments_decoded``: OSC messages + arguments handed to
    the decoder (each datagram at most ``max_osc_arguments``); ``contacts``: held
    now; ``contacts_dropped``: fingers refused by the contact limits; ``events``:
    contact events made; ``events_dropped``: of those, dropped before a poll took
    them; ``sources_tracked``: health entries held now; ``sources_forgotten``:
    entries forgotten (idle or evicted).
    """

    datagrams: int
    arguments_decoded: int
    contacts: int
    contacts_dropped: int
    events: int
    events_dropped: int
    sources_tracked: int
    sources_forgotten: int

