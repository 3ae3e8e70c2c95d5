"""A sandboxed decentralised run's network lives on the trusted side (issue 28.2).

The script's process never models the network: :class:`RemoteNetwork` stands in for
:class:`~swarmdeck.network.Network` there (``Decentralised`` asks the robots for it, ``PipeRobots.remote_network``).
Messages, child → parent:

* ``{"t": "decentralised", "topology": {...}, "loss": {...} | None, "latency", "jitter", "max_message_bytes",
  "bandwidth", "max_messages_per_tick", "seed"}`` once: the network the script asked for
  (:func:`network_config_message`; the trusted side rebuilds and checks it, :func:`network_config_from_message`);
* ``{"t": "outbox", "k": k, "messages": [[i, j, bytes], ...]}`` before tick k's commands: what the robots' controllers
  sent (j = −1: a broadcast), already encoded; the trusted :class:`~swarmdeck.network.Network` checks each one
  (sizes, counts, ids: refusals counted, :class:`TrustedNetwork`).

Parent → child, before each tick's poses: ``{"t": "inboxes", "k", "in": [[sender, receiver, sent_tick, bytes]],
"links", "messages", "bytes" (int64 bytes), "stats": {...}}`` — the deliveries of the network stepped at the robots'
true positions after the commands were certified, the topology (each robot's neighbours) and the counts.
"""
from __future__ import annotations

from collections import Counter, deque
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.console.sandbox.protocol import ProtocolError
from swarmdeck.network import NetworkConfig
from swarmdeck.network.errors import MessageError
from swarmdeck.network.loss import BernoulliLoss, GilbertElliottLoss
from swarmdeck.network.network import Message, Network, NetworkTraffic
from swarmdeck.network.payload import decode_payload, encode_payload
from swarmdeck.network.topology import DiskTopology, FixedTopology, KNearestTopology

__all__ = ["RemoteNetwork", "TrustedNetwork", "network_config_from_message", "network_config_message"]

_INTS = ("latency", "jitter", "max_message_bytes", "bandwidth", "max_messages_per_tick", "seed")


def network_config_message(config: NetworkConfig) -> dict[str, Any]:
    """The child's ``decentralised`` message for ``config``; ValueError naming a topology or loss model that cannot
    cross (a sandboxed run takes swarmdeck's own: they are rebuilt and checked on the trusted side)."""
    topo = config.topology
    if isinstance(topo, FixedTopology):
        topology: dict[str, Any] = {"kind": "fixed", "edges": [list(e) for e in topo.edges]}
    elif isinstance(topo, DiskTopology):
        topology = {"kind": "disk", "delta": float(topo.delta)}
    elif isinstance(topo, KNearestTopology):
        topology = {"kind": "knearest", "k": int(topo.k)}
    else:
        raise ValueError(f"a sandboxed decentralised run takes FixedTopology, DiskTopology or KNearestTopology "
                         f"(the trusted side models the network), got {type(topo).__name__}")
    loss = config.loss
    lossy: dict[str, Any] | None = None
    if isinstance(loss, BernoulliLoss):
        lossy = {"kind": "bernoulli", "p": float(loss.p)}
    elif isinstance(loss, GilbertElliottLoss):
        lossy = {"kind": "gilbert_elliott", "p": float(loss.p), "r": float(loss.r), "k_good": float(loss.k_good),
                 "k_bad": float(loss.k_bad)}
    return {"t": "decentralised", "topology": topology, "loss": lossy, **{k: getattr(config, k) for k in _INTS}}


def network_config_from_message(message: dict[str, Any]) -> NetworkConfig:
    """The :class:`~swarmdeck.network.NetworkConfig` of a ``decentralised`` message; ProtocolError naming what is
    not valid."""
    try:
        topo = message["topology"]
        kind = topo["kind"]
        if kind == "fixed":
            topology: Any = FixedTopology.from_edges(np.asarray(topo["edges"], dtype=np.int64).reshape(-1, 2))
        elif kind == "disk":
            topology = DiskTopology(float(topo["delta"]))
        elif kind == "knearest":
            topology = KNearestTopology(int(topo["k"]))
        else:
            raise ValueError(f"unknown topology {kind!r}")
        raw = message.get("loss")
        loss: BernoulliLoss | GilbertElliottLoss | None = None
        if raw is not None:
            if raw["kind"] == "bernoulli":
                loss = BernoulliLoss(float(raw["p"]))
            elif raw["kind"] == "gilbert_elliott":
                loss = GilbertElliottLoss(float(raw["p"]), float(raw["r"]), float(raw["k_good"]), float(raw["k_bad"]))
            else:
                raise ValueError(f"unknown loss model {raw['kind']!r}")
        ints: dict[str, Any] = {k: message.get(k) for k in _INTS if message.get(k) is not None}
        return NetworkConfig(topology=topology, loss=loss, **ints)
    except (KeyError, TypeError, ValueError, OverflowError) as exc:
        raise ProtocolError(f"'decentralised' message: not a network configuration: {exc!s:.200}") from None


def _ints(array: ArrayLike) -> bytes:
    return np.ascontiguousarray(array, dtype="<i8").tobytes()


class TrustedNetwork:
    """The trusted side's network of a sandboxed decentralised run: robots' messages in (:meth:`post`), one step at
    the true positions after each tick (:meth:`step`), the deliveries out (:meth:`inboxes_message`)."""

    def __init__(self, n: int, config: NetworkConfig, positions: ArrayLike) -> None:
        self.n, self.config = int(n), config
        self.network = Network(self.n, config, positions=positions)

    def post(self, message: dict[str, Any]) -> None:
        """An ``outbox`` message: every message handed to the network, which checks and counts it (a refused one is
        counted in ``network.stats``, never an error of the run); ProtocolError when the message is malformed."""
        items = message.get("messages")
        most = self.n * self.config.max_messages_per_tick
        if not isinstance(items, list) or len(items) > most:
            raise ProtocolError(f"'outbox' message: messages must be a list of at most {most} [i, j, bytes]")
        net = self.network
        for item in items:
            if (not isinstance(item, list) or len(item) != 3 or not all(isinstance(v, int) for v in item[:2])
                    or not isinstance(item[2], bytes)):
                raise ProtocolError(f"'outbox' message: each message must be [sender, receiver (-1: all), bytes], "
                                    f"got {str(item)[:80]!r}")
            i, j, data = item
            try:
                if j == -1:
                    net.broadcast_encoded(i, data)
                else:
                    net.send_encoded(i, j, data)
            except (MessageError, ValueError):
                pass  # refused and counted by the network (a bad id, too big, too many)

    def step(self, positions: ArrayLike) -> NetworkTraffic:
        """One network step at the robots' positions ``(N, 2)`` m; the traffic."""
        self.network.step(np.asarray(positions, dtype=float)[:, :2])
        return self.network.traffic()

    def inboxes_message(self, k: int) -> dict[str, Any]:
        """The ``inboxes`` message for tick ``k``."""
        net = self.network
        delivered = [[s, i, t, d] for i in range(self.n) for s, t, d in net.encoded_inbox(i)]
        traffic = net.traffic()
        return {"t": "inboxes", "k": int(k), "in": delivered, "links": _ints(traffic.links),
                "messages": _ints(traffic.messages), "bytes": _ints(traffic.bytes), "stats": dict(net.stats)}


class RemoteNetwork:
    """The script's process's stand-in for :class:`~swarmdeck.network.Network` (the same interface as far as
    ``devices.decentralised`` uses it): sends are queued for the trusted side, inboxes and neighbours are the
    trusted side's deliveries, ``step`` does nothing (the trusted side steps at the true positions)."""

    def __init__(self, n: int, config: NetworkConfig) -> None:
        self.n, self.config = int(n), config
        self.stats: Counter[str] = Counter()
        self.errors: deque[str] = deque(maxlen=50)
        self._outgoing: list[list[Any]] = []
        self._in: list[list[tuple[int, int, bytes]]] = [[] for _ in range(self.n)]
        self._traffic = NetworkTraffic(np.zeros((0, 2), np.intp), np.zeros(0, np.int64), np.zeros(0, np.int64))

    def send_encoded(self, i: int, j: int, data: bytes) -> None:
        self._outgoing.append([int(i), int(j), bytes(data)])

    def broadcast_encoded(self, i: int, data: bytes) -> int:
        self._outgoing.append([int(i), -1, bytes(data)])
        return len(self.neighbours(i))

    def send(self, i: int, j: int, payload: Any) -> None:
        self.send_encoded(i, j, encode_payload(payload, self.config.max_message_bytes))

    def broadcast(self, i: int, payload: Any) -> int:
        return self.broadcast_encoded(i, encode_payload(payload, self.config.max_message_bytes))

    def step(self, positions: ArrayLike) -> None:
        """Nothing: the trusted side steps the network."""

    def take_outgoing(self) -> list[list[Any]]:
        """The messages sent since the last call (the ``outbox`` message's list)."""
        out, self._outgoing = self._outgoing, []
        return out

    def deliver(self, message: dict[str, Any]) -> None:
        """The trusted side's ``inboxes`` message."""
        boxes: list[list[tuple[int, int, bytes]]] = [[] for _ in range(self.n)]
        for s, i, t, d in message["in"]:
            boxes[i].append((s, t, d))
        self._in = boxes
        links = np.frombuffer(message["links"], dtype="<i8").reshape(-1, 2).astype(np.intp)
        self._traffic = NetworkTraffic(links, np.frombuffer(message["messages"], dtype="<i8").astype(np.int64),
                                       np.frombuffer(message["bytes"], dtype="<i8").astype(np.int64))
        self.stats = Counter(message.get("stats") or {})

    def neighbours(self, i: int) -> NDArray[np.intp]:
        """Robots ``i`` can send to over the last step's links, ascending (as ``Network.neighbours``)."""
        links = self._traffic.links
        return np.sort(links[links[:, 0] == i, 1]) if len(links) else np.zeros(0, np.intp)

    def inbox(self, i: int) -> tuple[Message, ...]:
        return tuple(Message(s, i, t, decode_payload(d)) for s, t, d in self._in[i])

    def traffic(self) -> NetworkTraffic:
        return self._traffic

    @property
    def links(self) -> NDArray[np.intp]:
        return self._traffic.links.copy()

    @property
    def refused(self) -> int:
        return sum(v for k, v in self.stats.items() if k.startswith("refused:"))
