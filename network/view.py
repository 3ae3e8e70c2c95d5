"""What one robot's decentralised controller sees: :class:`RobotView`, and nothing else.

A view holds robot ``i``'s own pose (it knows where it is, as a Robotarium robot is told), the time and tick,
the messages delivered to it (:class:`~swarmdeck.network.network.Message`, fresh copies), its own sensor
readings (whatever the trusted side's sensors give for robot ``i``), its own persistent ``state`` (a dict the
controller may change; it is kept for robot ``i`` only) and the robots it can currently reach. It holds no
reference to the arena, the network or another robot: ``send``/``broadcast`` only append to the view's own
outbox, checked against the network's limits, and the trusted side hands the outbox to the network after the
controller returns. Reading any other attribute raises :class:`IsolationError` naming it and the robot.
"""
from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmdeck.network.errors import IsolationError, MessageError, PayloadError
from swarmdeck.network.network import Message
from swarmdeck.network.payload import encode_payload

__all__ = ["Outbox", "RobotView"]

_SEEN = ("i", "pose", "position", "time", "tick", "inbox", "readings", "state", "neighbours", "send", "broadcast")


class Outbox:
    """Robot ``i``'s messages of one tick, checked as :meth:`Network.send` checks them (ids, itself, size, count)."""

    __slots__ = ("i", "n", "max_bytes", "max_count", "fanout", "count", "messages", "refusals")

    def __init__(self, i: int, n: int, max_bytes: int, max_count: int, fanout: int) -> None:
        self.i, self.n, self.max_bytes, self.max_count = i, n, max_bytes, max_count
        self.fanout = fanout  # receivers of a broadcast (each counts as one message)
        self.count = 0
        self.messages: list[tuple[int | None, bytes]] = []  # (receiver or None for broadcast, encoding)
        self.refusals: list[tuple[str, str]] = []  # (reason, message)

    def _refuse(self, reason: str, text: str) -> MessageError:
        self.refusals.append((reason, text))
        return PayloadError(text) if reason in ("too_big", "unserialisable") else MessageError(text)

    def add(self, j: int | None, payload: Any, tick: int) -> None:
        i = self.i
        if j is not None:
            if isinstance(j, bool) or not isinstance(j, (int, np.integer)):
                raise self._refuse("unknown_robot", f"robot {i}, tick {tick}: receiver must be a robot index, got {j!r}")
            if not 0 <= int(j) < self.n:
                raise self._refuse("unknown_robot", f"robot {i}, tick {tick}: receiver {int(j)} does not exist: "
                                                    f"the robots are 0..{self.n - 1}")
            if int(j) == i:
                raise self._refuse("to_itself", f"robot {i}, tick {tick}: a robot cannot send a message to itself")
        copies = self.fanout if j is None else 1
        if self.count + copies > self.max_count:
            raise self._refuse("too_many", f"robot {i}, tick {tick}: more than {self.max_count} messages in one tick "
                                           "(max_messages_per_tick); this one is dropped")
        try:
            data = encode_payload(payload, self.max_bytes)
        except PayloadError as exc:
            reason = "too_big" if "exceeds" in str(exc) else "unserialisable"
            raise self._refuse(reason, f"robot {i}, tick {tick}: {exc}") from None
        self.messages.append((None if j is None else int(j), data))
        self.count += copies


class RobotView:
    """Robot ``i``'s view of one tick (see the module docstring); build one per robot per tick."""

    __slots__ = ("_i", "_pose", "_time", "_tick", "_inbox", "_readings", "_state", "_neighbours", "_outbox")

    def __init__(self, i: int, pose: NDArray[np.float64], time: float, tick: int, inbox: tuple[Message, ...],
                 readings: Any, state: dict[str, Any], neighbours: NDArray[np.intp], outbox: Outbox) -> None:
        pose = np.array(pose, dtype=float)
        pose.flags.writeable = False
        nb = np.array(neighbours, dtype=np.intp)
        nb.flags.writeable = False
        object.__setattr__(self, "_i", int(i))
        object.__setattr__(self, "_pose", pose)
        object.__setattr__(self, "_time", float(time))
        object.__setattr__(self, "_tick", int(tick))
        object.__setattr__(self, "_inbox", inbox)
        object.__setattr__(self, "_readings", readings)
        object.__setattr__(self, "_state", state)
        object.__setattr__(self, "_neighbours", nb)
        object.__setattr__(self, "_outbox", outbox)

    @property
    def i(self) -> int:
        """This robot's index, 0..N−1."""
        return self._i

    @property
    def pose(self) -> NDArray[np.float64]:
        """This robot's pose ``(3,)`` ``[x, y, θ]`` (m, rad), read-only."""
        return self._pose

    @property
    def position(self) -> NDArray[np.float64]:
        """This robot's position ``(2,)`` m, read-only."""
        return self._pose[:2]

    @property
    def time(self) -> float:
        """Experiment time, s."""
        return self._time

    @property
    def tick(self) -> int:
        """The control tick, counted from 0."""
        return self._tick

    @property
    def inbox(self) -> tuple[Message, ...]:
        """Messages delivered to this robot since its last tick, in delivery order."""
        return self._inbox

    @property
    def readings(self) -> Any:
        """This robot's own sensor readings (None without sensors)."""
        return self._readings

    @property
    def state(self) -> dict[str, Any]:
        """This robot's own memory, kept between ticks (change it freely)."""
        return self._state

    @property
    def neighbours(self) -> NDArray[np.intp]:
        """Robots this one can send to now (its radio's neighbour table), ascending, read-only."""
        return self._neighbours

    def send(self, j: int, payload: Any) -> None:
        """Send ``payload`` to robot ``j`` (delivered as the network allows); MessageError if refused."""
        self._outbox.add(j, payload, self._tick)

    def broadcast(self, payload: Any) -> None:
        """Send ``payload`` to every robot in :attr:`neighbours`; MessageError if refused."""
        self._outbox.add(None, payload, self._tick)

    def __getattr__(self, name: str) -> Any:
        raise IsolationError(f"robot {self._i}'s controller read {name!r}: a decentralised controller sees only "
                             f"its own view ({', '.join(_SEEN)}), not other robots' poses or the arena")

    def __setattr__(self, name: str, value: Any) -> None:
        raise IsolationError(f"robot {self._i}'s controller set {name!r} on its view: keep memory in view.state")

    def __repr__(self) -> str:
        return f"RobotView(i={self._i}, tick={self._tick}, inbox={len(self._inbox)} messages)"
