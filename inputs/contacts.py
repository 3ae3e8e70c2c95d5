"""Contact table (frames → calibrated contacts and events, timeouts) and the
per-source health book (rates, last seen, error and quirk counters).

Timeouts (issue 6 §4; REFERENCE.md §6: none of the reference TUIO clients has
one): a source whose last accepted frame is older than ``timeout`` (default 1 s)
is *lost* — every contact of it ends with a ``lost`` event and one
``source_lost`` event is emitted; its decoder state is forgotten so a restarted
sender is accepted whatever its frame numbers. Points of partial sources (OSC
point streams) also end (``up``) after their ``presence_timeout``.

Velocities: the sender's, mapped through the calibration, when it sends a
non-zero one; otherwise an exponentially smoothed finite difference of arena
positions over receive times, capped at ``max_speed``.
"""
from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable

import numpy as np

from .calibration import Calibration
from .contact import Contact, ContactEvent, SourceHealth
from .frames import SourceFrame

MAX_EVENTS = 10_000
#: Most sources (health entries, contact sources) kept; beyond it the least
#: recently seen ones without contacts are forgotten (ephemeral peers such as
#: reconnecting TCP tablets or one-shot senders would otherwise pile up).
MAX_SOURCES = 1024


class _Health:
    __slots__ = ("kind", "times", "datagrams", "last_seen", "errors", "warnings", "last_error")

    def __init__(self, kind: str) -> None:
        self.kind = kind
        self.times: deque = deque()
        self.datagrams = 0
        self.last_seen = -math.inf
        self.errors: dict[str, int] = {}
        self.warnings: dict[str, int] = {}
        self.last_error: str | None = None


class HealthBook:
    """Counters per source name. Implements the decoders' ``Problems`` protocol."""

    def __init__(self, rate_window: float = 1.0) -> None:
        self._rate_window = rate_window
        self._entries: dict[str, _Health] = {}

    def _get(self, name: str, kind: str) -> _Health:
        h = self._entries.get(name)
        if h is None:
            if len(self._entries) >= MAX_SOURCES:
                oldest = min(self._entries, key=lambda n: self._entries[n].last_seen)
                del self._entries[oldest]
            h = self._entries[name] = _Health(kind)
        return h

    def seen(self, name: str, kind: str, t: float) -> None:
        """Count one datagram for ``name`` received at ``t``."""
        h = self._get(name, kind)
        h.datagrams += 1
        h.last_seen = t
        times = h.times
        times.append(t)
        lim = t - self._rate_window
        while times and times[0] <= lim:
            times.popleft()

    def error(self, name: str, kind: str, reason: str, detail: str) -> None:
        """Count rejected input."""
        h = self._get(name, kind)
        h.errors[reason] = h.errors.get(reason, 0) + 1
        h.last_error = detail

    def warn(self, name: str, kind: str, reason: str) -> None:
        """Count accepted input with a quirk."""
        h = self._get(name, kind)
        h.warnings[reason] = h.warnings.get(reason, 0) + 1

    def snapshot(self, now: float, contacts: dict[str, int], lost: set[str]) -> tuple[SourceHealth, ...]:
        """Frozen health records, sorted by name."""
        out = []
        lim = now - self._rate_window
        for name in sorted(self._entries):
            h = self._entries[name]
            rate = sum(1 for x in h.times if lim < x <= now) / self._rate_window
            out.append(SourceHealth(name, h.kind, rate, h.last_seen, h.datagrams, contacts.get(name, 0),
                                    name in lost, dict(h.errors), dict(h.warnings), h.last_error))
        return tuple(out)


# Internal contact state: (px, py, vx, vy, size, pressure, kind, class_id, first_seen, last_seen);
# immutable tuples, materialised into Contact objects only when polled.
_PX, _PY, _VX, _VY, _SIZE, _PRESS, _KIND, _CLS, _FIRST, _LAST = range(10)


def _contact(name: str, sid: int, st: tuple) -> Contact:
    """Materialise a state tuple. ``Contact`` is a frozen dataclass; filling its
    ``__dict__`` directly skips the per-field ``object.__setattr__`` of the
    generated ``__init__`` (4× faster; same object, still immutable)."""
    c = object.__new__(Contact)
    c.__dict__.update(source=name, id=sid, position=np.array((st[_PX], st[_PY])),
                      velocity=np.array((st[_VX], st[_VY])), size=st[_SIZE], pressure=st[_PRESS],
                      kind=st[_KIND], class_id=st[_CLS], first_seen=st[_FIRST], last_seen=st[_LAST])
    return c


class _Source:
    __slots__ = ("name", "a", "b", "area_scale", "last_seen", "lost", "presence_timeout", "states")

    def __init__(self, name: str, cal: Calibration) -> None:
        self.name = name
        a, b = cal.matrix()
        self.a = tuple(float(v) for v in a.ravel())
        self.b = (float(b[0]), float(b[1]))
        self.area_scale = cal.area_scale()
        self.last_seen = -math.inf
        self.lost = False
        self.presence_timeout: float | None = None
        self.states: dict[int, tuple] = {}


class ContactTable:
    """Current contacts of every source of one listener, with events and timeouts.

    Args:
        calibration_for: source name → its :class:`Calibration`.
        timeout: s of silence after which a source is lost (> 0).
        on_lost: called with the name of a source that was just lost.
        velocity_smoothing: weight of the newest finite-difference velocity (0..1].
        max_speed: m/s cap on finite-difference velocities.
    """

    def __init__(self, calibration_for: Callable[[str], Calibration], timeout: float = 1.0,
                 on_lost: Callable[[str], None] | None = None, velocity_smoothing: float = 0.5,
                 max_speed: float = 5.0) -> None:
        if not timeout > 0:
            raise ValueError(f"timeout must be > 0 s, got {timeout}")
        if not 0 < velocity_smoothing <= 1:
            raise ValueError(f"velocity_smoothing must be in (0, 1], got {velocity_smoothing}")
        self._cal_for = calibration_for
        self._timeout = float(timeout)
        self._on_lost = on_lost
        self._alpha = float(velocity_smoothing)
        self._max_speed = float(max_speed)
        self._sources: dict[str, _Source] = {}
        # raw events (kind, source, id, t, state|None), materialised on drain
        self._events: deque[tuple] = deque(maxlen=MAX_EVENTS)
        self._cache: tuple[Contact, ...] | None = ()
        self._objects: dict[int, tuple] = {}  # id(state) -> (state, Contact)

    @property
    def timeout(self) -> float:
        """Seconds of silence before a source is lost."""
        return self._timeout

    def apply(self, frame: SourceFrame, t: float) -> None:
        """Apply one committed frame received at ``t``."""
        src = self._sources.get(frame.source)
        if src is None:
            if len(self._sources) >= MAX_SOURCES:
                idle = [n for n, x in self._sources.items() if not x.states]
                if idle:
                    del self._sources[min(idle, key=lambda n: self._sources[n].last_seen)]
            src = self._sources[frame.source] = _Source(frame.source, self._cal_for(frame.source))
        src.last_seen = t
        src.lost = False
        src.presence_timeout = frame.presence_timeout
        push = self._events.append
        name = src.name
        states = src.states
        if frame.restart:
            for sid, st in states.items():
                push(("up", name, sid, t, st))
            states.clear()
        a00, a01, a10, a11 = src.a
        b0, b1 = src.b
        alpha = self._alpha
        points = frame.points
        for sid, e in points.items():
            x, y, vx, vy, area, press, kind, cls = e
            px = a00 * x + a01 * y + b0
            py = a10 * x + a11 * y + b1
            old = states.get(sid)
            if vx == vx and (vx != 0.0 or vy != 0.0):
                wx = a00 * vx + a01 * vy
                wy = a10 * vx + a11 * vy
            elif old is not None:
                dt = t - old[_LAST]
                if dt > 1e-6:
                    wx = alpha * (px - old[_PX]) / dt + (1.0 - alpha) * old[_VX]
                    wy = alpha * (py - old[_PY]) / dt + (1.0 - alpha) * old[_VY]
                    sp = math.hypot(wx, wy)
                    if sp > self._max_speed:
                        wx *= self._max_speed / sp
                        wy *= self._max_speed / sp
                else:
                    wx, wy = old[_VX], old[_VY]
            else:
                wx = wy = 0.0
            size = 2.0 * math.sqrt(area * src.area_scale / math.pi) if area == area and area >= 0 else None
            if old is None:
                st = (px, py, wx, wy, size, press if press == press else None, kind, cls, t, t)
                push(("down", name, sid, t, st))
            else:
                st = (px, py, wx, wy, size, press if press == press else None, kind, cls, old[_FIRST], t)
                if old[_PX] != px or old[_PY] != py or old[_VX] != wx or old[_VY] != wy:
                    push(("move", name, sid, t, st))
            states[sid] = st
        if frame.complete and len(states) > len(points):  # states ⊇ frame ids here
            for sid in [s for s in states if s not in points]:
                push(("up", name, sid, t, states.pop(sid)))
        self._cache = None  # states were replaced (last_seen) even when nothing moved

    def expire(self, now: float) -> None:
        """End contacts of sources silent for longer than the timeout and points
        past their presence timeout, as of ``now``."""
        push = self._events.append
        for src in self._sources.values():
            if src.lost:
                continue
            if now - src.last_seen > self._timeout:
                for sid, st in src.states.items():
                    push(("lost", src.name, sid, now, st))
                src.states.clear()
                src.lost = True
                push(("source_lost", src.name, None, now, None))
                self._cache = None
                if self._on_lost is not None:
                    self._on_lost(src.name)
            elif src.presence_timeout is not None:
                lim = now - src.presence_timeout
                gone = [sid for sid, st in src.states.items() if st[_LAST] < lim]
                for sid in gone:
                    push(("up", src.name, sid, now, src.states.pop(sid)))
                if gone:
                    self._cache = None

    def _materialise(self, name: str, sid: int, st: tuple) -> Contact:
        # one Contact object per state tuple, shared by contacts() and events
        c = self._objects.get(id(st))
        if c is None or c[0] is not st:
            c = self._objects[id(st)] = (st, _contact(name, sid, st))
        return c[1]

    def contacts(self) -> tuple[Contact, ...]:
        """All current contacts (a tuple; contacts are immutable)."""
        if self._cache is None:
            self._cache = tuple(self._materialise(s.name, sid, st) for s in self._sources.values()
                                for sid, st in s.states.items())
            self._prune_objects()
        return self._cache

    def drain_events(self) -> list[ContactEvent]:
        """Events since the previous call (oldest first; at most 10 000 kept)."""
        out = [ContactEvent(k, name, sid, t, None if st is None else self._materialise(name, sid, st))
               for k, name, sid, t, st in self._events]
        self._events.clear()
        self._prune_objects()
        return out

    def _prune_objects(self) -> None:
        if len(self._objects) > 4 * (sum(len(s.states) for s in self._sources.values()) + 64):
            live = {id(st) for s in self._sources.values() for st in s.states.values()}
            self._objects = {k: v for k, v in self._objects.items() if k in live}

    def counts(self) -> dict[str, int]:
        """Number of contacts per source name."""
        return {n: len(s.states) for n, s in self._sources.items()}

    def lost(self) -> set[str]:
        """Names of sources currently lost."""
        return {n for n, s in self._sources.items() if s.lost}
