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

#: Most sources (health entries, contact sources) kept; beyond it the least
#: recently heard ones are forgotten (ephemeral peers such as reconnecting TCP
#: tablets or one-shot senders would otherwise pile up).
MAX_SOURCES = 1024
#: Receive times kept per source for its rate (a flood shows as >= this many per window).
RATE_SAMPLES = 256
#: Longest ``last_error`` kept (a hostile datagram's repr must not fill a page).
MAX_DETAIL = 200


class _Health:
    __slots__ = ("kind", "times", "datagrams", "last_seen", "errors", "warnings", "last_error")

    def __init__(self, kind: str) -> None:
        self.kind = kind
        self.times: deque = deque(maxlen=RATE_SAMPLES)
        self.datagrams = 0
        self.last_seen = -math.inf
        self.errors: dict[str, int] = {}
        self.warnings: dict[str, int] = {}
        self.last_error: str | None = None

    def heard(self, t: float, window: float) -> None:
        """One datagram at ``t``: count it, keep its time while within ``window``."""
        self.datagrams += 1
        self.last_seen = t
        times = self.times
        times.append(t)
        lim = t - window
        while times[0] <= lim:
            times.popleft()

    def rate(self, now: float, window: float) -> float:
        lim = now - window
        return sum(1 for x in self.times if lim < x <= now) / window


class HealthBook:
    """Counters per source name, and the listener's lifetime totals. Implements the
    decoders' ``Problems`` protocol.

    Entries are kept in order of last activity; :meth:`expire` forgets those silent
    for longer than ``forget_after`` (O(forgotten): the oldest are at the front).
    Every error and warning is also added to the totals, which are never forgotten.
    """

    def __init__(self, rate_window: float = 1.0, forget_after: float = 30.0, name: str = "listener",
                 max_sources: int = MAX_SOURCES) -> None:
        self._rate_window = rate_window
        self._forget_after = float(forget_after)
        self._max_sources = max_sources
        self._entries: dict[str, _Health] = {}
        self.name = name
        self._totals = _Health("listener")
        self.forgotten = 0

    def __len__(self) -> int:
        return len(self._entries)

    def _get(self, name: str, kind: str) -> _Health:
        h = self._entries.get(name)
        if h is None:
            if len(self._entries) >= self._max_sources:  # forget the least recently heard
                del self._entries[next(iter(self._entries))]
                self.forgotten += 1
            h = self._entries[name] = _Health(kind)
        return h

    def datagram(self, t: float) -> None:
        """Count one datagram received by the listener at ``t`` (the totals' rate)."""
        self._totals.heard(t, self._rate_window)

    def seen(self, name: str, kind: str, t: float) -> None:
        """Count one datagram for ``name`` received at ``t``."""
        h = self._entries.pop(name, None)  # re-insert: most recently heard last
        if h is None:
            h = self._get(name, kind)
        else:
            self._entries[name] = h
        h.heard(t, self._rate_window)

    def error(self, name: str, kind: str, reason: str, detail: str, n: int = 1) -> None:
        """Count ``n`` rejected inputs (the listener's own name counts only in the totals)."""
        detail = detail if len(detail) <= MAX_DETAIL else detail[:MAX_DETAIL - 1] + "…"
        tot = self._totals
        tot.errors[reason] = tot.errors.get(reason, 0) + n
        tot.last_error = detail
        if name != self.name:
            h = self._get(name, kind)
            h.errors[reason] = h.errors.get(reason, 0) + n
            h.last_error = detail

    def warn(self, name: str, kind: str, reason: str, n: int = 1) -> None:
        """Count ``n`` accepted inputs with a quirk."""
        tot = self._totals
        tot.warnings[reason] = tot.warnings.get(reason, 0) + n
        if name != self.name:
            h = self._get(name, kind)
            h.warnings[reason] = h.warnings.get(reason, 0) + n

    def expire(self, now: float, keep: Callable[[str], bool]) -> list[str]:
        """Forget entries silent for longer than ``forget_after`` as of ``now``
        unless ``keep(name)`` (a source that still has contacts); their names.
        Walks from the least recently heard and stops at the first recent one."""
        lim = now - self._forget_after
        entries = self._entries
        gone: list[str] = []
        kept: list[str] = []
        for name, h in entries.items():
            if h.last_seen >= lim:
                break
            (kept if keep(name) else gone).append(name)
        for name in gone:
            del entries[name]
        for name in kept:  # still has contacts: to the back, looked at again later
            entries[name] = entries.pop(name)
        self.forgotten += len(gone)
        return gone

    def _record(self, name: str, h: _Health, now: float, contacts: int, lost: bool) -> SourceHealth:
        return SourceHealth(name, h.kind, h.rate(now, self._rate_window), h.last_seen, h.datagrams, contacts,
                            lost, dict(h.errors), dict(h.warnings), h.last_error)

    def totals(self, now: float, contacts: int, **extra: int) -> SourceHealth:
        """The listener's lifetime totals as one record (kind ``"listener"``): all
        datagrams, every error and warning by reason, ``extra`` counters as warnings."""
        h = self._totals
        rec = self._record(self.name, h, now, contacts, False)
        rec.warnings.update({k: v for k, v in extra.items() if v})
        return rec

    def snapshot(self, now: float, contacts: dict[str, int], lost: set[str] | Callable[[str], bool],
                 limit: int | None = None) -> tuple[SourceHealth, ...]:
        """Frozen health records sorted by name: all, or at most ``limit`` — the
        sources in ``contacts`` first, then the most recently heard — plus one
        ``"<name>: N more sources"`` record (kind ``"more"``) when some are left out."""
        is_lost = lost.__contains__ if isinstance(lost, (set, frozenset)) else lost
        entries = self._entries
        if limit is None or len(entries) <= limit:
            names = list(entries)
        else:
            names = [n for n in contacts if n in entries][:limit]
            chosen = set(names)
            for n in reversed(entries):
                if len(names) >= limit:
                    break
                if n not in chosen:
                    names.append(n)
        out = [self._record(n, entries[n], now, contacts.get(n, 0), is_lost(n)) for n in sorted(names)]
        hidden = len(entries) - len(names)
        if hidden:
            out.append(SourceHealth(f"{self.name}: {hidden} more sources", "more", 0.0, -math.inf, 0, 0, False))
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


def _affine(cal: Calibration) -> tuple:
    """``(a (4,), b (2,), area_scale)`` of a calibration as plain floats."""
    a, b = cal.matrix()
    return tuple(float(v) for v in a.ravel()), (float(b[0]), float(b[1])), cal.area_scale()


class _Source:
    __slots__ = ("name", "a", "b", "area_scale", "last_seen", "lost", "presence_timeout", "states")

    def __init__(self, name: str, affine: tuple) -> None:
        self.name = name
        self.a, self.b, self.area_scale = affine
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
        max_per_source, max_total: contacts one source / all sources may hold; new
            fingers beyond them are dropped and counted on ``problems`` as
            ``too_many_contacts`` (a frame's missing fingers are removed first, so a
            source replacing its fingers keeps its share).
        max_events: events kept between drains (older ones dropped and counted).
        forget_after: s after which a lost source is forgotten.
        problems: where dropped contacts are counted (``error(name, kind, reason, detail, n)``).
    """

    def __init__(self, calibration_for: Callable[[str], Calibration], timeout: float = 1.0,
                 on_lost: Callable[[str], None] | None = None, velocity_smoothing: float = 0.5,
                 max_speed: float = 5.0, max_per_source: int = 64, max_total: int = 256,
                 max_events: int = 1024, forget_after: float = 30.0, problems=None) -> None:
        if not timeout > 0:
            raise ValueError(f"timeout must be > 0 s, got {timeout}")
        if not 0 < velocity_smoothing <= 1:
            raise ValueError(f"velocity_smoothing must be in (0, 1], got {velocity_smoothing}")
        self._cal_for = calibration_for
        self._timeout = float(timeout)
        self._on_lost = on_lost
        self._alpha = float(velocity_smoothing)
        self._max_speed = float(max_speed)
        self._max_per_source = int(max_per_source)
        self._max_total = int(max_total)
        self._forget_after = max(float(forget_after), self._timeout)
        self._problems = problems
        self._sources: dict[str, _Source] = {}
        self._affines: dict[int, tuple] = {}  # id(calibration) -> (calibration, its affine map)
        self._n = 0  # contacts of all sources
        # raw events (kind, source, id, t, state|None), materialised on drain
        self._events: deque[tuple] = deque(maxlen=int(max_events))
        self.events_total = 0
        self.events_dropped = 0
        self._cache: tuple[Contact, ...] | None = ()
        self._objects: dict[int, tuple] = {}  # id(state) -> (state, Contact)

    @property
    def timeout(self) -> float:
        """Seconds of silence before a source is lost."""
        return self._timeout

    def __len__(self) -> int:
        """Number of current contacts (all sources)."""
        return self._n

    def _push(self, ev: tuple) -> None:
        events = self._events
        if len(events) == events.maxlen:
            self.events_dropped += 1
        events.append(ev)
        self.events_total += 1

    def apply(self, frame: SourceFrame, t: float) -> None:
        """Apply one committed frame received at ``t``."""
        sources = self._sources
        src = sources.pop(frame.source, None)
        if src is None:
            if len(sources) >= MAX_SOURCES:  # forget the least recently heard without contacts
                for n, x in sources.items():  # at most max_total + 1 steps: few sources have contacts
                    if not x.states:
                        del sources[n]
                        break
            cal = self._cal_for(frame.source)
            affine = self._affines.get(id(cal))
            if affine is None or affine[0] is not cal:
                affine = self._affines[id(cal)] = (cal, _affine(cal))
            src = _Source(frame.source, affine[1])
        sources[frame.source] = src  # most recently heard last
        src.last_seen = t
        src.lost = False
        src.presence_timeout = frame.presence_timeout
        push = self._push
        name = src.name
        states = src.states
        points = frame.points
        if frame.restart:
            for sid, st in states.items():
                push(("up", name, sid, t, st))
            self._n -= len(states)
            states.clear()
        if frame.complete and states:  # ids missing from a complete frame are gone: first
            gone = [sid for sid in states if sid not in points]
            for sid in gone:
                push(("up", name, sid, t, states.pop(sid)))
            self._n -= len(gone)
        a00, a01, a10, a11 = src.a
        b0, b1 = src.b
        alpha = self._alpha
        room = min(self._max_per_source - len(states), self._max_total - self._n)
        dropped = 0
        for sid, e in points.items():
            old = states.get(sid)
            if old is None:
                if room <= 0:
                    dropped += 1
                    continue
                room -= 1
                self._n += 1
            x, y, vx, vy, area, press, kind, cls = e
            px = a00 * x + a01 * y + b0
            py = a10 * x + a11 * y + b1
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
        if dropped and self._problems is not None:
            full = len(states) >= self._max_per_source
            self._problems.error(name, frame.kind, "too_many_contacts",
                                 f"{dropped} new contact(s) dropped: the limit of "
                                 + (f"{self._max_per_source} contacts per source" if full else
                                    f"{self._max_total} contacts in total") + " was reached", dropped)
        self._cache = None  # states were replaced (last_seen) even when nothing moved

    def expire(self, now: float) -> None:
        """End contacts of sources silent for longer than the timeout and points
        past their presence timeout, as of ``now``; forget sources lost for longer
        than ``forget_after``."""
        push = self._push
        forget = []
        for src in self._sources.values():
            if src.lost:
                if now - src.last_seen > self._forget_after:
                    forget.append(src.name)
                continue
            if now - src.last_seen > self._timeout:
                for sid, st in src.states.items():
                    push(("lost", src.name, sid, now, st))
                self._n -= len(src.states)
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
                    self._n -= len(gone)
                    self._cache = None
        for name in forget:
            del self._sources[name]

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
        """Events since the previous call (oldest first; at most ``max_events`` kept)."""
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
        """Number of contacts per source name, for the sources that have some."""
        return {n: len(s.states) for n, s in self._sources.items() if s.states}

    def is_lost(self, name: str) -> bool:
        """Whether the source ``name`` is currently lost."""
        s = self._sources.get(name)
        return s is not None and s.lost

    def lost(self) -> set[str]:
        """Names of sources currently lost."""
        return {n for n, s in self._sources.items() if s.lost}
