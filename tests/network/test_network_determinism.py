"""The same seed and the same sends give the same deliveries, bit for bit; another seed gives others."""
from __future__ import annotations

import numpy as np

from swarmdeck.network import DiskTopology, GilbertElliottLoss, Network, NetworkConfig


def _trace(seed: int) -> list[tuple[int, int, int, int, int]]:
    rng = np.random.default_rng(0)  # the same positions and sends for every seed
    n = 12
    cfg = NetworkConfig(topology=DiskTopology(0.6), latency=1, jitter=2,
                        loss=GilbertElliottLoss(p=0.1, r=0.3, k_good=0.05, k_bad=0.9), bandwidth=400, seed=seed)
    pos = rng.uniform(-1, 1, (n, 2))
    net = Network(n, cfg, positions=pos)
    out = []
    for tick in range(60):
        for i in range(n):
            net.broadcast(i, {"i": i, "t": tick, "v": rng.normal(size=3)})
        pos = pos + rng.normal(scale=0.02, size=pos.shape)
        net.step(pos)
        out += [(tick, m.sender, m.receiver, m.sent_tick, int(m.payload["i"])) for i in range(n) for m in net.inbox(i)]
    return out


def test_same_seed_same_deliveries_other_seed_others():
    a, b, c = _trace(42), _trace(42), _trace(43)
    assert a == b and len(a) > 100
    assert a != c
