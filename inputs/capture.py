"""Raw datagram capture and socket-free replay.

A :class:`Datagram` is exactly what the ``on_datagram`` hook sees (bytes, peer,
transport, receive time). :class:`Capture` is a ready-made hook that keeps them;
:func:`replay` feeds captured datagrams back through the *same* parser on a
virtual clock (the receive times), so a recorded session re-simulates exactly.
JSON Lines (``{"t": s, "peer": "udp://h:p", "transport": "udp", "data": base64}``)
is a small diff-friendly file format for fixtures.
"""
from __future__ import annotations

import base64
import json
import threading
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path

from .listener import InputSource, peer_name


@dataclass(frozen=True)
class Datagram:
    """One received datagram: raw ``data``, ``peer`` name, ``transport`` and receive time ``t`` (s)."""

    t: float
    data: bytes
    peer: str
    transport: str = "udp"

    def to_json(self) -> str:
        """One JSON Lines record."""
        return json.dumps({"t": self.t, "peer": self.peer, "transport": self.transport,
                           "data": base64.b64encode(self.data).decode("ascii")})

    @classmethod
    def from_json(cls, line: str) -> Datagram:
        """Parse one JSON Lines record; ``ValueError`` naming the problem."""
        try:
            d = json.loads(line)
            return cls(float(d["t"]), base64.b64decode(d["data"], validate=True), str(d["peer"]),
                       str(d.get("transport", "udp")))
        except (KeyError, TypeError, ValueError) as exc:
            raise ValueError(f"not a datagram record ({{t, peer, transport, data}}): {exc}") from None


class Capture:
    """An ``on_datagram`` hook that keeps every datagram (thread-safe)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._items: list[Datagram] = []

    def __call__(self, data: bytes, peer: object, transport: str, t: float) -> None:
        d = Datagram(float(t), bytes(data), peer_name(transport, peer), transport)
        with self._lock:
            self._items.append(d)

    def datagrams(self) -> list[Datagram]:
        """A copy of everything captured so far, in arrival order."""
        with self._lock:
            return list(self._items)


def replay(datagrams: Iterable[Datagram], source: InputSource, time_offset: float = 0.0) -> int:
    """Feed ``datagrams`` into ``source`` at their receive times (+ ``time_offset``);
    returns how many were fed. The caller polls ``source`` as its clock advances."""
    n = 0
    for d in datagrams:
        source.feed(d.data, d.peer, d.t + time_offset, d.transport)
        n += 1
    return n


def write_jsonl(path: str | Path, datagrams: Iterable[Datagram]) -> None:
    """Write datagrams as JSON Lines."""
    with open(path, "w", encoding="utf-8") as f:
        for d in datagrams:
            f.write(d.to_json() + "\n")


def read_jsonl(path: str | Path) -> Iterator[Datagram]:
    """Read datagrams written by :func:`write_jsonl` (``ValueError`` names the line)."""
    with open(path, encoding="utf-8") as f:
        for i, line in enumerate(f, 1):
            if line.strip():
                try:
                    yield Datagram.from_json(line)
                except ValueError as exc:
                    raise ValueError(f"{path}:{i}: {exc}") from None
