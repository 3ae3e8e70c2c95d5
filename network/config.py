"""The network's configuration: one frozen dataclass (REFERENCE.md §16)."""
from __future__ import annotations

from dataclasses import dataclass, field

from swarmdeck.network.loss import BernoulliLoss, GilbertElliottLoss
from swarmdeck.network.topology import DiskTopology, FixedTopology, KNearestTopology, Topology

__all__ = ["DEFAULT_MAX_MESSAGE_BYTES", "DEFAULT_MAX_MESSAGES_PER_TICK", "MAX_LATENCY_TICKS", "NetworkConfig"]

#: Largest encoded message, bytes (a few hundred floats; the GRITSBot's WiFi frame is ~1.5 kB).
DEFAULT_MAX_MESSAGE_BYTES = 4096
#: Most messages one robot may queue in one tick (a broadcast counts once per receiver).
DEFAULT_MAX_MESSAGES_PER_TICK = 64
#: Longest latency + jitter, ticks (about 33 s at the control period): bounds what the network holds.
MAX_LATENCY_TICKS = 1000


def _whole(name: str, value: object, lo: int, hi: int | None = None) -> None:
    if isinstance(value, bool) or not isinstance(value, int) or value < lo or (hi is not None and value > hi):
        bound = f"in {lo}..{hi}" if hi is not None else f">= {lo}"
        raise ValueError(f"NetworkConfig.{name} must be an integer {bound}, got {value!r}")


@dataclass(frozen=True)
class NetworkConfig:
    """How robots can talk.

    Attributes:
        topology: who hears whom (:class:`FixedTopology`, :class:`DiskTopology`, :class:`KNearestTopology`).
        latency: fixed delay, whole ticks: 0 delivers a message at the end of the tick it was sent in (it is in
            the receiver's inbox the next tick), L delivers it L ticks later.
        jitter: extra delay drawn uniformly from 0..jitter ticks per message (so messages can overtake).
        loss: None (lossless), :class:`BernoulliLoss` or :class:`GilbertElliottLoss`.
        max_message_bytes: largest encoded message, bytes.
        bandwidth: bytes one robot may send per tick (sum over its messages, in send order; the rest are dropped
            and counted), None for no limit.
        max_messages_per_tick: messages one robot may queue per tick; the next ``send`` raises.
        seed: seeds loss and jitter; the same seed and the same sends give the same deliveries.
    """

    topology: Topology = field(default_factory=lambda: DiskTopology(0.5))
    latency: int = 0
    jitter: int = 0
    loss: BernoulliLoss | GilbertElliottLoss | None = None
    max_message_bytes: int = DEFAULT_MAX_MESSAGE_BYTES
    bandwidth: int | None = None
    max_messages_per_tick: int = DEFAULT_MAX_MESSAGES_PER_TICK
    seed: int | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.topology, (FixedTopology, DiskTopology, KNearestTopology, Topology)):
            raise ValueError(f"NetworkConfig.topology must be a topology, got {self.topology!r}")
        _whole("latency", self.latency, 0, MAX_LATENCY_TICKS)
        _whole("jitter", self.jitter, 0, MAX_LATENCY_TICKS - self.latency)
        if self.loss is not None and not isinstance(self.loss, (BernoulliLoss, GilbertElliottLoss)):
            raise ValueError(f"NetworkConfig.loss must be None, BernoulliLoss or GilbertElliottLoss, got {self.loss!r}")
        _whole("max_message_bytes", self.max_message_bytes, 1)
        if self.bandwidth is not None:
            _whole("bandwidth", self.bandwidth, 1)
        _whole("max_messages_per_tick", self.max_messages_per_tick, 1)
        if self.seed is not None:
            _whole("seed", self.seed, 0)
