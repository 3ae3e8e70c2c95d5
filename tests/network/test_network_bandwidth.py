"""A robot's messages beyond its bytes-per-tick budget are dropped and counted, in send order; other robots
keep their own budget (REFERENCE.md §16: bandwidth as bytes per robot per tick)."""
from __future__ import annotations

import numpy as np

from swarmdeck.network import DiskTopology, Network, NetworkConfig, encode_payload

POS = np.zeros((3, 2))


def test_bandwidth_caps_each_senders_bytes_per_tick():
    payload = np.zeros(20)  # encodes to a fixed size
    size = len(encode_payload(payload, 4096))
    net = Network(3, NetworkConfig(topology=DiskTopology(1.0), bandwidth=3 * size + size // 2), positions=POS)
    for k in range(5):
        net.send(0, 1 + k % 2, payload)
    net.send(1, 0, payload)
    net.step(POS)
    # robot 0: the first three fit (3 · size ≤ budget), the fourth and fifth do not; robot 1's own budget is untouched
    assert len(net.inbox(1)) + len(net.inbox(2)) == 3 and len(net.inbox(0)) == 1
    assert net.stats["over_bandwidth"] == 2
    assert sorted(m.sent_tick for m in net.inbox(1) + net.inbox(2)) == [0, 0, 0]
    # the budget is per tick: next tick robot 0 can send three again
    for _ in range(4):
        net.send(0, 1, payload)
    net.step(POS)
    assert len(net.inbox(1)) == 3 and net.stats["over_bandwidth"] == 3


def test_unreachable_messages_do_not_use_the_budget():
    payload = "x" * 100
    size = len(encode_payload(payload, 4096))
    pos = np.array([[0.0, 0.0], [0.1, 0.0], [5.0, 0.0]])
    net = Network(3, NetworkConfig(topology=DiskTopology(1.0), bandwidth=size), positions=pos)
    net.send(0, 2, payload)  # no link: unreachable, costs nothing
    net.send(0, 1, payload)
    net.step(pos)
    assert len(net.inbox(1)) == 1 and net.stats["unreachable"] == 1 and net.stats["over_bandwidth"] == 0
