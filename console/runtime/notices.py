"""What a tick tells the operator besides its numbers: messages (``Frame.events``), standing alerts
(``Frame.alerts``) and error counts (``ControlLoop.errors``), shared by the operator commands and the tick.

Thread-safe: the loop thread, GUI callbacks and the portal post from any thread.
"""
from __future__ import annotations

import threading


class Notices:
    """Messages for the next Frame, alerts by key (shown while they stand) and errors counted by stage."""

    def __init__(self, lock: threading.RLock | None = None) -> None:
        self.lock = lock if lock is not None else threading.RLock()
        self.errors: dict[str, int] = {}
        self._events: list[str] = []
        self._alerts: dict[str, str] = {}

    def post(self, message: str) -> None:
        """Add a message to the next Frame's events."""
        with self.lock:
            self._events.append(str(message))

    def alert(self, key: str, message: str | None, event: bool = True) -> None:
        """Raise (or with None clear) the standing alert ``key``; a new text is also an event (``event``)."""
        with self.lock:
            if message is None:
                self._alerts.pop(key, None)
            elif self._alerts.get(key) != message:
                self._alerts[key] = message
                if event:
                    self._events.append(message)

    def standing(self, key: str, message: str) -> None:
        """Set alert ``key`` to ``message`` without an event (it has been posted in other words)."""
        with self.lock:
            self._alerts[key] = message

    def count(self, what: str) -> None:
        """One more error of ``what`` (a stage, "listener", "tick", …)."""
        with self.lock:
            self.errors[what] = self.errors.get(what, 0) + 1

    def take(self) -> tuple[tuple[str, ...], tuple[str, ...]]:
        """The messages since the last call (cleared) and the alerts standing now."""
        with self.lock:
            events = tuple(self._events)
            self._events.clear()
            return events, tuple(self._alerts.values())
