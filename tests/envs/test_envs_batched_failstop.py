"""A swarm whose barrier cannot certify stops alone: its commands are zero and it is named, the other swarms get
exactly what one filter per swarm gives them."""
from __future__ import annotations

import numpy as np

from swarmdeck.core.kinematics import GritsBotParams
from swarmdeck.envs.batched_barrier import BatchedDistributedBarrier
from swarmdeck.safety import BarrierConfig, UnicycleSafetyFilter


def test_one_failing_swarm_stops_alone():
    params = GritsBotParams()
    cfg = BarrierConfig(mode="distributed")
    rng = np.random.default_rng(8)
    e_count, n = 3, 12
    xy = rng.uniform([-1.4, -0.8], [1.4, 0.8], (e_count, n, 2))
    poses = np.concatenate((xy, rng.uniform(-np.pi, np.pi, (e_count, n, 1))), axis=2)
    poses[1, 4, :2] = [3e6, 0.0]  # a tracking or units error in swarm 1
    flat = poses.reshape(-1, 3)
    v, w = rng.uniform(-0.2, 0.2, e_count * n), rng.uniform(-2, 2, e_count * n)
    res = BatchedDistributedBarrier(cfg, params).filter(flat, v, w, e_count)
    assert res.ok.tolist() == [True, False, True]
    assert "beyond" in res.reason[1] and res.reason[0] == res.reason[2] == ""
    assert not res.v[n:2 * n].any() and not res.w[n:2 * n].any()
    single = UnicycleSafetyFilter(cfg, params)
    for e in (0, 2):
        sl = slice(e * n, (e + 1) * n)
        vs, ws, diag = single.filter(flat[sl], v[sl], w[sl])
        assert diag.ok and np.array_equal(vs, res.v[sl]) and np.array_equal(ws, res.w[sl])
    _, _, diag = single.filter(flat[n:2 * n], v[n:2 * n], w[n:2 * n])
    assert not diag.ok  # the single filter refuses the same swarm
