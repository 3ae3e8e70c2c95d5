"""The communication graph of one tick, as a Frame carries it (issue 28 item 2; :mod:`swarmdeck.network`).

``Frame.network`` is a :class:`NetworkFrame` or None (no network: written only when present, so recordings
without it read as before). Fields: ``links`` ``(E, 2)`` int, directed (sender, receiver) robot indices into
the Frame's robots, this tick's topology; ``rate`` ``(E,)`` float, messages per second delivered over each
link this tick (messages / dt). JSON layout (:meth:`NetworkFrame.to_dict`): ``{"links": [[s, r], ...],
"rate": [...]}``; the recording codec packs them binary (``links`` int16/int32, ``rate`` float32).
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["NetworkFrame"]


def _ro(a: NDArray[Any]) -> NDArray[Any]:
    a = np.array(a)
    a.flags.writeable = False
    return a


@dataclass(frozen=True, eq=False)
class NetworkFrame:
    """One tick's links ``(E, 2)`` and per-link message rate ``(E,)`` messages/s (module docstring)."""

    links: NDArray[np.int64]
    rate: NDArray[np.float64]

    def __post_init__(self) -> None:
        links = np.asarray(self.links, dtype=np.int64).reshape(-1, 2)
        rate = np.asarray(self.rate, dtype=float).reshape(-1)
        if len(rate) != len(links):
            raise ValueError(f"frame field 'network': {len(links)} links but {len(rate)} rates")
        if links.size and links.min() < 0:
            raise ValueError("frame field 'network.links' names a negative robot index")
        if not np.all(np.isfinite(rate)) or (rate < 0).any():
            raise ValueError("frame field 'network.rate' must be finite and >= 0 messages/s")
        object.__setattr__(self, "links", _ro(links))
        object.__setattr__(self, "rate", _ro(rate))

    @classmethod
    def from_traffic(cls, links: ArrayLike, messages: ArrayLike, dt: float) -> NetworkFrame:
        """From a :class:`swarmdeck.network.NetworkTraffic`'s ``links`` and ``messages`` over a tick of ``dt`` s."""
        return cls(np.asarray(links, dtype=np.int64), np.asarray(messages, dtype=float) / float(dt))

    def to_dict(self) -> dict[str, Any]:
        return {"links": self.links.tolist(), "rate": self.rate.tolist()}

    @classmethod
    def from_dict(cls, d: Any) -> NetworkFrame:
        if not isinstance(d, Mapping) or "links" not in d or "rate" not in d:
            raise ValueError("frame field 'network' must be an object {links, rate}")
        return cls(np.asarray(d["links"], dtype=np.int64).reshape(-1, 2), np.asarray(d["rate"], dtype=float))

    def check_robots(self, n: int) -> None:
        """ValueError when a link names a robot outside 0..n−1."""
        if self.links.size and int(self.links.max()) >= n:
            raise ValueError(f"frame field 'network.links' names robot {int(self.links.max())}, outside 0..{n - 1}")
