"""Robot-to-robot messaging over a topology with latency, loss and bandwidth (REFERENCE.md §16).

One :class:`Network` per experiment, stepped once per control tick by whoever owns the robots' poses (the
trusted side). During a tick robots queue messages with :meth:`Network.send` / :meth:`Network.broadcast`;
:meth:`Network.step` then, in send order: drops messages without a link in the topology at the positions
``step`` is given — where the robots are when the tick closes — ("unreachable"; :meth:`Network.neighbours`, which
``broadcast`` uses, is the previous step's topology: a robot's neighbour table lags one tick), drops a sender's messages beyond its bandwidth ("over_bandwidth"), draws the loss model
("lost"), and schedules the rest ``latency + U{0..jitter}`` ticks later. What is due lands in the inboxes,
read with :meth:`Network.inbox` during the next tick. Everything random comes from one generator seeded by
:attr:`NetworkConfig.seed`.

Refusals at ``send`` (an unknown receiver or sender, a message to itself, a payload that is not serialisable
or too big, more than ``max_messages_per_tick`` in one tick) raise :class:`MessageError` naming the robot, the
tick and what was wrong, and are counted in :attr:`Network.stats` under ``refused:<reason>``; the network
itself is unchanged by a refused message.
"""
from __future__ import annotations

from collections import Counter, deque
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.network.config import NetworkConfig
from swarmdeck.network.errors import MessageError, PayloadError
from swarmdeck.network.loss import LossState
from swarmdeck.network.payload import decode_payload, encode_payload

__all__ = ["Message", "Network", "NetworkTraffic"]


class Message(NamedTuple):
    """A delivered message: ``sender`` → ``receiver`` (robot indices), sent in tick ``sent_tick``; ``payload`` is a copy."""

    sender: int
    receiver: int
    sent_tick: int
    payload: Any


@dataclass(frozen=True)
class NetworkTraffic:
    """One tick's communication graph and what crossed it.

    ``links`` ``(E, 2)`` int directed (sender, receiver) of this tick's topology; ``messages`` and ``bytes``
    ``(E,)`` int: messages delivered over each link in this tick and their encoded bytes.
    """

    links: NDArray[np.intp]
    messages: NDArray[np.int64]
    bytes: NDArray[np.int64]


def _index(name: str, value: object, n: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise MessageError(f"{name} must be a robot index (int), got {type(value).__name__} {value!r}")
    if not 0 <= int(value) < n:
        raise MessageError(f"{name} {int(value)} does not exist: the robots are 0..{n - 1}")
    return int(value)


class Network:
    """The messages between ``n`` robots under ``config``; see the module docstring for one tick.

    Args:
        n: number of robots.
        config: the network's configuration.
        positions: ``(n, 2)`` m, the robots' positions for the first tick's topology (none before the first
            :meth:`step` when omitted).
    """

    def __init__(self, n: int, config: NetworkConfig | None = None, positions: ArrayLike | None = None) -> None:
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
            raise ValueError(f"Network: number of robots must be an integer >= 1, got {n!r}")
        self.n = int(n)
        self.config = config if config is not None else NetworkConfig()
        self.tick = 0
        self.stats: Counter[str] = Counter()
        self.errors: deque[str] = deque(maxlen=50)  # the most recent refusals, for a report
        self._rng = np.random.default_rng(self.config.seed)
        self._loss_state = LossState()
        self._links = np.empty((0, 2), dtype=np.intp)
        # this tick's sends, in send order: senders, receivers, encodings
        self._qs: list[int] = []
        self._qr: list[int] = []
        self._qd: list[bytes] = []
        self._queued = np.zeros(self.n, dtype=np.int64)
        # due tick -> batches (senders, receivers, sent ticks, encodings) in flight
        self._pending: dict[int, list[tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64], list[bytes]]]] = {}
        # the last step's deliveries sorted by receiver (stable): senders, sent ticks, encodings, receiver row starts
        self._in_s = np.zeros(0, dtype=np.int64)
        self._in_sent = np.zeros(0, dtype=np.int64)
        self._in_data: list[bytes] = []
        self._in_start = np.zeros(self.n + 1, dtype=np.int64)
        self._traffic = NetworkTraffic(self._links, np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64))
        if positions is not None:
            self._links = self._topology(positions)
            self._traffic = NetworkTraffic(self._links, np.zeros(len(self._links), np.int64), np.zeros(len(self._links), np.int64))

    # -- sending -------------------------------------------------------------------------------------
    def _refuse(self, reason: str, message: str) -> MessageError:
        self.stats[f"refused:{reason}"] += 1
        self.errors.append(message)
        return PayloadError(message) if reason in ("unserialisable", "too_big") else MessageError(message)

    def _encode(self, sender: int, payload: Any) -> bytes:
        try:
            return encode_payload(payload, self.config.max_message_bytes)
        except PayloadError as exc:
            reason = "too_big" if "exceeds" in str(exc) else "unserialisable"
            raise self._refuse(reason, f"robot {sender}, tick {self.tick}: {exc}") from None

    def _sender(self, i: object) -> int:
        try:
            return _index("sender", i, self.n)
        except MessageError as exc:
            raise self._refuse("unknown_robot", f"tick {self.tick}: {exc}") from None

    def _room(self, i: int, count: int) -> None:
        cap = self.config.max_messages_per_tick
        if self._queued[i] + count > cap:
            raise self._refuse("too_many", f"robot {i}, tick {self.tick}: more than {cap} messages in one tick "
                                           f"(max_messages_per_tick); this one is dropped")

    def send(self, i: int, j: int, payload: Any) -> None:
        """Queue ``payload`` from robot ``i`` to robot ``j`` for this tick; :class:`MessageError` if refused."""
        i, j = self._pair(i, j)
        self._room(i, 1)
        self._enqueue(i, [j], self._encode(i, payload))

    def broadcast(self, i: int, payload: Any) -> int:
        """Queue ``payload`` from ``i`` to each of its current :meth:`neighbours`; returns how many were queued."""
        i = self._sender(i)
        receivers = self.neighbours(i)
        if not len(receivers):
            return 0
        self._room(i, len(receivers))
        self._enqueue(i, receivers.tolist(), self._encode(i, payload))
        return len(receivers)

    def send_encoded(self, i: int, j: int, data: bytes) -> None:
        """:meth:`send` of a payload already encoded by :func:`~swarmdeck.network.payload.encode_payload`."""
        i, j = self._pair(i, j)
        self._room(i, 1)
        self._enqueue(i, [j], self._sized(i, data))

    def broadcast_encoded(self, i: int, data: bytes) -> int:
        """:meth:`broadcast` of a payload already encoded."""
        i = self._sender(i)
        receivers = self.neighbours(i)
        if len(receivers):
            self._room(i, len(receivers))
            self._enqueue(i, receivers.tolist(), self._sized(i, data))
        return len(receivers)

    def _enqueue(self, i: int, receivers: list[int], data: bytes) -> None:
        k = len(receivers)
        self._qs.extend([i] * k)
        self._qr.extend(receivers)
        self._qd.extend([data] * k)
        self._queued[i] += k

    def _pair(self, i: object, j: object) -> tuple[int, int]:
        s = self._sender(i)
        try:
            r = _index("receiver", j, self.n)
        except MessageError as exc:
            raise self._refuse("unknown_robot", f"robot {s}, tick {self.tick}: {exc}") from None
        if s == r:
            raise self._refuse("to_itself", f"robot {s}, tick {self.tick}: a robot cannot send a message to itself")
        return s, r

    def _sized(self, i: int, data: bytes) -> bytes:
        if not isinstance(data, bytes) or len(data) > self.config.max_message_bytes:
            raise self._refuse("too_big", f"robot {i}, tick {self.tick}: encoded message of "
                                          f"{len(data) if isinstance(data, bytes) else '?'} bytes exceeds "
                                          f"{self.config.max_message_bytes} bytes")
        return data

    def neighbours(self, i: int) -> NDArray[np.intp]:
        """Robots ``i`` can send to under the current topology (the last :meth:`step`'s links), ascending."""
        i = _index("robot", i, self.n)
        lo, hi = np.searchsorted(self._links[:, 0], [i, i + 1])
        return self._links[lo:hi, 1].copy()

    # -- one tick --------------------------------------------------------------------------------------
    def _topology(self, positions: ArrayLike) -> NDArray[np.intp]:
        p = np.asarray(positions, dtype=float)
        if p.shape != (self.n, 2) or not np.all(np.isfinite(p)):
            raise ValueError(f"Network.step: positions must be finite, shape ({self.n}, 2), got shape {p.shape}")
        return self.config.topology.links(p)

    def step(self, positions: ArrayLike) -> None:
        """Close this tick: the topology at ``positions`` ``(n, 2)`` m, bandwidth, loss, latency; fill the inboxes."""
        links = self._topology(positions)
        s = np.array(self._qs, dtype=np.int64)
        r = np.array(self._qr, dtype=np.int64)
        data = self._qd
        self._qs, self._qr, self._qd = [], [], []
        self._queued[:] = 0
        n, tick, cfg = self.n, self.tick, self.config
        link_keys = links[:, 0].astype(np.int64) * n + links[:, 1]
        if cfg.loss is not None:
            self._loss_state = cfg.loss.advance(self._loss_state, link_keys, self._rng)
        if len(s):
            size = np.fromiter(map(len, data), dtype=np.int64, count=len(data))
            keys = s * n + r
            pos = np.minimum(np.searchsorted(link_keys, keys), max(len(link_keys) - 1, 0))
            ok = (link_keys[pos] == keys) if len(link_keys) else np.zeros(len(keys), dtype=bool)
            self.stats["sent"] += len(s)
            self.stats["unreachable"] += int((~ok).sum())
            if cfg.bandwidth is not None:  # cumulative bytes per sender, in send order, over reachable messages
                order = np.argsort(s, kind="stable")
                spent = np.where(ok, size, 0)[order]
                total = np.cumsum(spent)
                starts = np.r_[0, np.flatnonzero(np.diff(s[order])) + 1]
                before = np.repeat(total[starts] - spent[starts], np.diff(np.r_[starts, len(s)]))
                over = np.zeros(len(s), dtype=bool)
                over[order] = total - before > cfg.bandwidth
                over &= ok
                self.stats["over_bandwidth"] += int(over.sum())
                ok &= ~over
            if cfg.loss is not None and ok.any():
                lost = np.zeros(len(keys), dtype=bool)
                lost[ok] = cfg.loss.lost(self._loss_state, keys[ok], self._rng)
                self.stats["lost"] += int(lost.sum())
                ok &= ~lost
            delay = np.full(len(keys), cfg.latency, dtype=np.int64)
            if cfg.jitter:
                delay += self._rng.integers(0, cfg.jitter + 1, size=len(keys))
            keep = np.flatnonzero(ok)
            for d in np.unique(delay[keep]).tolist():
                sel = keep[delay[keep] == d]
                self._pending.setdefault(tick + int(d), []).append(
                    (s[sel], r[sel], np.full(len(sel), tick, dtype=np.int64), [data[k] for k in sel.tolist()]))
        self._deliver(self._pending.pop(tick, []))
        counts = np.zeros(len(links), dtype=np.int64)
        nbytes = np.zeros(len(links), dtype=np.int64)
        if len(self._in_s) and len(links):
            receivers = np.repeat(np.arange(n, dtype=np.int64), np.diff(self._in_start))
            dk = self._in_s * n + receivers
            at = np.minimum(np.searchsorted(link_keys, dk), len(link_keys) - 1)
            on = link_keys[at] == dk  # a message whose link is gone since it was sent is not on this tick's graph
            np.add.at(counts, at[on], 1)
            sizes = np.fromiter(map(len, self._in_data), dtype=np.int64, count=len(self._in_data))
            np.add.at(nbytes, at[on], sizes[on])
        self._links = links
        self._traffic = NetworkTraffic(links, counts, nbytes)
        self.tick = tick + 1

    def _deliver(self, batches: list[tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64], list[bytes]]]) -> None:
        """The inboxes of this tick: the batches due now, sorted by receiver (stable: delivery order kept)."""
        if not batches:
            self._in_s, self._in_sent, self._in_data = np.zeros(0, np.int64), np.zeros(0, np.int64), []
            self._in_start = np.zeros(self.n + 1, dtype=np.int64)
            return
        s = np.concatenate([b[0] for b in batches])
        r = np.concatenate([b[1] for b in batches])
        sent = np.concatenate([b[2] for b in batches])
        data = [d for b in batches for d in b[3]]
        order = np.argsort(r, kind="stable")
        self._in_s, self._in_sent = s[order], sent[order]
        self._in_data = [data[k] for k in order.tolist()]
        self._in_start = np.searchsorted(r[order], np.arange(self.n + 1))
        self.stats["delivered"] += len(s)

    # -- reading ---------------------------------------------------------------------------------------
    def inbox(self, i: int) -> tuple[Message, ...]:
        """Messages delivered to robot ``i`` by the last :meth:`step`, in delivery order; fresh copies each call."""
        i = _index("robot", i, self.n)
        lo, hi = int(self._in_start[i]), int(self._in_start[i + 1])
        senders, sent = self._in_s[lo:hi].tolist(), self._in_sent[lo:hi].tolist()
        return tuple(Message(s, i, t, decode_payload(d)) for s, t, d in zip(senders, sent, self._in_data[lo:hi]))

    def encoded_inbox(self, i: int) -> tuple[tuple[int, int, bytes], ...]:
        """Robot ``i``'s inbox as :meth:`inbox` has it, payloads still encoded: ``(sender, sent_tick, data)`` each (what
        the sandbox's trusted side sends to the script's process)."""
        i = _index("robot", i, self.n)
        lo, hi = int(self._in_start[i]), int(self._in_start[i + 1])
        return tuple(zip(self._in_s[lo:hi].tolist(), self._in_sent[lo:hi].tolist(), self._in_data[lo:hi]))

    def traffic(self) -> NetworkTraffic:
        """The last step's links and the messages and bytes delivered over each."""
        return self._traffic

    @property
    def links(self) -> NDArray[np.intp]:
        """The last step's directed links ``(E, 2)``."""
        return self._links.copy()

    @property
    def refused(self) -> int:
        """How many messages were refused at send."""
        return sum(v for k, v in self.stats.items() if k.startswith("refused:"))
