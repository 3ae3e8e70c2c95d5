"""The event list of the console's panel and of the player: repeats collapse into one line ("× 120").

A failing script behaviour raises on every tick, often with a message that differs only in its
numbers ("boom at t=0.033", "boom at t=0.066", …); listed one by one, those lines pushed the rest
of the panel down. :class:`EventLog` keeps the last ``size`` *distinct* events: an event whose
text equals the newest one's up to its numbers (:func:`event_shape`) is counted into that line,
which then shows the newest text, its time and "× N".
"""
from __future__ import annotations

import re
import threading
from collections import deque

_NUMBER = re.compile(r"[-+]?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?")


def event_shape(text: str) -> str:
    """``text`` with every number replaced by ``#``: two events of one shape are repeats."""
    return _NUMBER.sub("#", text)


class EventLog:
    """The last ``size`` events, repeats collapsed (thread-safe: one thread adds, another reads).

    Args:
        size: lines kept (the oldest drop off).
    """

    def __init__(self, size: int) -> None:
        self._lock = threading.Lock()
        self._rows: deque[tuple[float, str, int]] = deque(maxlen=size)  # (t s, newest text, repeats)

    def add(self, t: float, text: str) -> None:
        """Add the event ``text`` at session time ``t`` s."""
        with self._lock:
            if self._rows and event_shape(self._rows[-1][1]) == event_shape(text):
                self._rows[-1] = (float(t), text, self._rows[-1][2] + 1)
            else:
                self._rows.append((float(t), text, 1))

    def rows(self) -> list[tuple[float, str, int]]:
        """(session t s of the newest repeat, its text, how many), oldest first."""
        with self._lock:
            return list(self._rows)

    def lines(self) -> list[str]:
        """``"12.3 s · text"``, with ``" × N"`` after a line that stands for N repeats."""
        return [f"{t:.1f} s · {text}" + (f" × {n}" if n > 1 else "") for t, text, n in self.rows()]

    def __len__(self) -> int:
        return len(self._rows)
