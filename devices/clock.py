"""Clocks: a virtual clock for simulation and tests, and real-time pacing on request."""
from __future__ import annotations

import time
from dataclasses import dataclass, field


@dataclass
class VirtualClock:
    """Simulated time in seconds, advanced only by :meth:`advance`."""

    now: float = 0.0

    def advance(self, dt: float) -> float:
        """Move time forward by ``dt`` s and return the new time."""
        if not dt >= 0:
            raise ValueError(f"dt must be >= 0, got {dt!r}")
        self.now += dt
        return self.now


@dataclass
class RealTimePacer:
    """Sleeps so that successive :meth:`wait` calls are ``period`` s apart on the monotonic clock.

    Falls behind gracefully: after an overrun it re-anchors instead of bursting
    to catch up, and counts the overruns.
    """

    period: float
    overruns: int = 0
    _next: float | None = field(default=None, repr=False)

    def wait(self) -> None:
        """Block until the next period boundary."""
        now = time.monotonic()
        if self._next is None:
            self._next = now + self.period
            return
        delay = self._next - now
        if delay > 0:
            time.sleep(delay)
            self._next += self.period
        else:
            self.overruns += 1
            self._next = now + self.period
