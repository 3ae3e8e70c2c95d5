"""Robot-to-robot messaging and the decentralised view (issue 28 item 2; REFERENCE.md §16).

:class:`Network` carries messages between robots over a :class:`FixedTopology`, :class:`DiskTopology` or
:class:`KNearestTopology`, with latency, :class:`BernoulliLoss` or :class:`GilbertElliottLoss`, message-size
and bandwidth limits, all deterministic under :attr:`NetworkConfig.seed`. :class:`RobotView` is all a
decentralised controller sees (``swarmdeck.devices.decentralised`` runs them). Imports only ``swarmdeck.core``.
"""
from __future__ import annotations

from swarmdeck.network.config import NetworkConfig
from swarmdeck.network.errors import IsolationError, MessageError, PayloadError
from swarmdeck.network.loss import BernoulliLoss, GilbertElliottLoss
from swarmdeck.network.network import Message, Network, NetworkTraffic
from swarmdeck.network.payload import decode_payload, encode_payload
from swarmdeck.network.topology import DiskTopology, FixedTopology, KNearestTopology, Topology
from swarmdeck.network.view import Outbox, RobotView

__all__ = ["BernoulliLoss", "DiskTopology", "FixedTopology", "GilbertElliottLoss", "IsolationError",
           "KNearestTopology", "Message", "MessageError", "Network", "NetworkConfig", "NetworkTraffic", "Outbox",
           "PayloadError", "RobotView", "Topology", "decode_payload", "encode_payload"]
