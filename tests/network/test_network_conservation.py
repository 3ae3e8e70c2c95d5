"""Invariants of the network over random sends, motions and configurations (hypothesis): every accepted message is
delivered, lost, unreachable or over the bandwidth exactly once, or still in flight; a delivered message crossed a
link of the topology that closed the tick it was sent in (at the positions the robots reached), arrives latency … latency + jitter ticks later, unchanged, and never to its
sender; no robot sends more than its budget in a tick."""
from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.network import (
    BernoulliLoss,
    DiskTopology,
    GilbertElliottLoss,
    KNearestTopology,
    MessageError,
    Network,
    NetworkConfig,
    encode_payload,
)

configs = st.builds(
    NetworkConfig,
    topology=st.one_of(st.builds(DiskTopology, st.floats(0.2, 2.0)), st.builds(KNearestTopology, st.integers(1, 4))),
    latency=st.integers(0, 3), jitter=st.integers(0, 2),
    loss=st.one_of(st.none(), st.builds(BernoulliLoss, st.floats(0.0, 1.0)),
                   st.builds(GilbertElliottLoss, st.floats(0.01, 1.0), st.floats(0.01, 1.0), st.floats(0, 1), st.floats(0, 1))),
    max_message_bytes=st.integers(16, 200), bandwidth=st.one_of(st.none(), st.integers(20, 300)),
    max_messages_per_tick=st.integers(1, 8), seed=st.integers(0, 2**16))


@settings(max_examples=60)
@given(configs, st.integers(2, 8), st.integers(0, 2**16))
def test_every_message_is_accounted_for_once(config, n, seed):
    rng = np.random.default_rng(seed)
    pos = rng.uniform(-1.0, 1.0, (n, 2))
    net = Network(n, config, positions=pos)
    accepted: dict[int, tuple[int, int, int]] = {}  # -> (sender, receiver, tick)
    closing: dict[int, set] = {}  # tick -> the links of the step that closed it
    arrivals = []
    ticks = 12
    for tick in range(ticks):
        spent = np.zeros(n, dtype=int)
        for _ in range(int(rng.integers(0, 3 * n))):
            i, j = int(rng.integers(0, n)), int(rng.integers(0, n))
            mid = len(accepted) + 1000 * tick
            payload = {"id": mid, "pad": "x" * int(rng.integers(0, 60))}
            try:
                if rng.random() < 0.3:
                    k = net.broadcast(i, payload)
                    for r in net.neighbours(i).tolist():
                        accepted[len(accepted)] = (i, r, tick)
                    spent[i] += k
                else:
                    net.send(i, j, payload)
                    accepted[len(accepted)] = (i, j, tick)
                    spent[i] += 1
            except MessageError:
                pass
        assert (spent <= config.max_messages_per_tick).all()
        pos = np.clip(pos + rng.normal(scale=0.2, size=pos.shape), -1.5, 1.5)
        net.step(pos)
        closing[tick] = {tuple(x) for x in net.links.tolist()}
        for r in range(n):
            for m in net.inbox(r):
                assert m.receiver == r and m.sender != r
                assert config.latency <= tick - m.sent_tick <= config.latency + config.jitter
                arrivals.append((m.sender, r, m.sent_tick, tick))
    st_ = net.stats
    assert st_["sent"] == len(accepted)
    in_flight = len(accepted) - st_["delivered"] - st_["lost"] - st_["unreachable"] - st_["over_bandwidth"]
    assert 0 <= in_flight
    if config.latency + config.jitter == 0:
        assert in_flight == 0
    assert st_["delivered"] == len(arrivals)
    for s, r, sent, _ in arrivals:  # a delivered message was sent, over a link of the step that closed its tick
        assert (s, r, sent) in set(accepted.values()) and (s, r) in closing[sent]
    if config.bandwidth is None:
        assert st_["over_bandwidth"] == 0
    assert encode_payload({"id": 1}, 100)  # the payloads above are message values
