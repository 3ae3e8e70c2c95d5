"""Loss statistics over seeded runs (REFERENCE.md §16): the Bernoulli rate and the Gilbert–Elliott stationary
loss and mean burst length fall within confidence bounds. Seeded, so each run is the same run; the bounds are
wide enough (≥ 4.5 standard errors) that any seed would pass."""
from __future__ import annotations

import numpy as np

from swarmdeck.network import BernoulliLoss, FixedTopology, GilbertElliottLoss, Network, NetworkConfig

N_LINKS = 100  # robots 2k -> 2k+1
TICKS = 400


def _run(loss, seed: int) -> np.ndarray:
    """(TICKS, N_LINKS) bool: whether the one message sent on each link each tick was delivered."""
    n = 2 * N_LINKS
    edges = np.column_stack((np.arange(0, n, 2), np.arange(1, n, 2)))
    net = Network(n, NetworkConfig(topology=FixedTopology.from_edges(edges), loss=loss, seed=seed),
                  positions=np.zeros((n, 2)))
    out = np.zeros((TICKS, N_LINKS), dtype=bool)
    for t in range(TICKS):
        for a in range(N_LINKS):
            net.send(2 * a, 2 * a + 1, t)
        net.step(np.zeros((n, 2)))
        for a in range(N_LINKS):
            out[t, a] = any(m.payload == t for m in net.inbox(2 * a + 1))
    assert net.stats["lost"] + net.stats["delivered"] == TICKS * N_LINKS
    return out


def test_bernoulli_loss_rate_within_bounds():
    for p in (0.1, 0.5):
        delivered = _run(BernoulliLoss(p), seed=3)
        m = delivered.size
        rate = 1.0 - delivered.mean()
        assert abs(rate - p) < 4.5 * np.sqrt(p * (1 - p) / m), (p, rate)


def test_gilbert_elliott_stationary_loss_and_burst_length_within_bounds():
    model = GilbertElliottLoss(p=0.05, r=0.25, k_good=0.0, k_bad=1.0)
    delivered = _run(model, seed=11)
    lost = ~delivered
    expected = model.stationary_loss()  # p / (p + r) = 1/6
    assert abs(expected - 0.05 / 0.30) < 1e-12
    # the per-link losses are a Markov chain with correlation ρ = 1 − p − r per tick: the variance of the
    # mean over T ticks grows by (1 + ρ)/(1 − ρ); links are independent
    rho = 1 - model.p - model.r
    se = np.sqrt(expected * (1 - expected) / lost.size * (1 + rho) / (1 - rho))
    assert abs(lost.mean() - expected) < 4.5 * se, (lost.mean(), expected, se)
    # bursts (runs of losses on one link, k_bad = 1, k_good = 0): mean length 1/r = 4 ticks
    runs = []
    for a in range(N_LINKS):
        x = np.r_[0, lost[:, a].astype(int), 0]
        starts, ends = np.flatnonzero(np.diff(x) == 1), np.flatnonzero(np.diff(x) == -1)
        runs += (ends - starts).tolist()
    runs_arr = np.array(runs, dtype=float)
    # run lengths are geometric(r): mean 1/r, sd sqrt(1 − r)/r
    assert abs(runs_arr.mean() - 1 / model.r) < 4.5 * np.sqrt(1 - model.r) / model.r / np.sqrt(len(runs_arr))


def test_lossless_by_default_and_k_good_alone_is_bernoulli():
    assert _run(None, seed=0).all()
    delivered = _run(GilbertElliottLoss(p=0.0, r=1.0, k_good=0.2, k_bad=1.0), seed=5)  # never Bad
    assert abs((1 - delivered.mean()) - 0.2) < 4.5 * np.sqrt(0.2 * 0.8 / delivered.size)
