"""``InputHub``: several listeners merged into one view for the console.

Typical use in the console loop::

    hub = InputHub.from_config(InputConfig.load_toml("swarmdeck.toml"), clock=loop_clock,
                               on_datagram=recorder.raw_datagram)
    density = ContactDensity(hub.config.density)
    with hub:                               # binds every socket, starts the threads
        while running:
            now = loop_clock()
            snap = hub.poll(now)            # contacts, events since last poll, health
            density.update(snap.contacts, now)
            controller.density = density    # once; the controller calls density.at(t)
"""
from __future__ import annotations

import time
from collections.abc import Callable, Sequence

from .config import InputConfig
from .contact import Contact, InputSnapshot, SourceHealth
from .listener import DatagramHook, InputSource, make_listener


class InputHub:
    """Merges the snapshots of several :class:`InputSource` s (usually listeners).

    Args:
        sources: the sources to merge (more can be added with :meth:`add`).
        clock: used by :meth:`poll` when ``now`` is omitted.
        config: the configuration the hub was built from, if any.
    """

    def __init__(self, sources: Sequence[InputSource] = (), *, clock: Callable[[], float] = time.monotonic,
                 config: InputConfig | None = None) -> None:
        self._sources: list[InputSource] = list(sources)
        self._clock = clock
        self.config = config or InputConfig()

    @classmethod
    def from_config(cls, config: InputConfig, *, clock: Callable[[], float] = time.monotonic,
                    on_datagram: DatagramHook | None = None) -> InputHub:
        """One UDP/TCP listener per ``config.listeners`` entry (not started)."""
        return cls([make_listener(lc, clock=clock, on_datagram=on_datagram) for lc in config.listeners],
                   clock=clock, config=config)

    @property
    def sources(self) -> tuple[InputSource, ...]:
        """The merged sources."""
        return tuple(self._sources)

    def add(self, source: InputSource) -> None:
        """Merge one more source."""
        self._sources.append(source)

    def start(self) -> InputHub:
        """Start every source (binds sockets); on failure, close what started and re-raise."""
        started = []
        try:
            for s in self._sources:
                s.start()
                started.append(s)
        except Exception:
            for s in started:
                s.close()
            raise
        return self

    def close(self) -> None:
        """Close every source."""
        for s in self._sources:
            s.close()

    def __enter__(self) -> InputHub:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.close()

    def poll(self, now: float | None = None) -> InputSnapshot:
        """Poll every source: all contacts (one per ``(source, id)``), all events
        since the previous poll (ordered by time), all health records.

        ``now`` (default ``clock()``) stamps the snapshot and is the poll time of
        socket-free sources (replays); socket listeners are polled on their own
        receive clock, so contact/event times are on that clock."""
        t = self._clock() if now is None else float(now)
        # socket listeners are polled on their own receive clock, so their timeouts
        # hold whatever clock the caller's `now` is on (a ghost finger must not
        # survive a clock mix-up); socket-free sources are polled at `now`
        snaps = [s.poll(s.poll_time(t)) for s in self._sources]
        contacts = self._dedupe(c for s in snaps for c in s.contacts)
        events = tuple(sorted((e for s in snaps for e in s.events), key=lambda e: e.t))
        health = tuple(h for s in snaps for h in s.health)
        return InputSnapshot(t, contacts, events, health)

    def contacts(self) -> tuple[Contact, ...]:
        """Current contacts of every source (no expiry, no events drained)."""
        return self._dedupe(c for s in self._sources for c in s.contacts())

    @staticmethod
    def _dedupe(contacts) -> tuple[Contact, ...]:
        """One contact per ``(source, id)``: a sender that reaches two listeners
        (reacTIVision can send to several ports) is the same finger; keep the newest.
        Sources are named by sending host and TUIO source string, so two senders on
        one host without source strings are one sender here too (as within a listener)."""
        out: dict = {}
        for c in contacts:
            old = out.get(c.key)
            if old is None or c.last_seen >= old.last_seen:
                out[c.key] = c
        return tuple(out.values())

    def health(self, now: float | None = None) -> tuple[SourceHealth, ...]:
        """Health of every source (socket listeners on their own clock)."""
        t = self._clock() if now is None else float(now)
        return tuple(h for s in self._sources for h in s.health(s.poll_time(t)))
