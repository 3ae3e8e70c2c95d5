"""Scenario S1 of REFERENCE.md §5 reproduced: t = 0 values, mean H per law and the law order."""
from __future__ import annotations

import numpy as np
import pytest

from swarmdeck.coverage import coverage_tick, s1_density
from swarmdeck.coverage.scenario import S1_REFERENCE, S1_T0, format_s1_table, run_s1_all, s1_config, s1_start


def test_t0_values():
    _, st, _ = coverage_tick(s1_start(), s1_density().at(0.0), s1_config("lloyd"), 0.0)
    assert st.cost_H == pytest.approx(S1_T0["H"], rel=1e-5)
    assert st.masses.sum() == pytest.approx(S1_T0["mass"], rel=1e-5)
    i = int(np.flatnonzero((st.positions == [-1.0, -0.5]).all(axis=1))[0])
    c, dc = np.array(S1_T0["c"]), np.array(S1_T0["dc_dt"])
    assert np.linalg.norm(st.centroids[i] - c) <= 1e-5 * np.linalg.norm(c)
    assert np.linalg.norm(st.dc_dt[i] - dc) <= 1e-5 * np.linalg.norm(dc)


@pytest.mark.slow
def test_mean_cost_per_law_and_order():
    results = run_s1_all()
    for law, (mean_h, mean_d) in S1_REFERENCE.items():
        r = results[law]
        assert r.H.shape == (1212,)
        assert r.mean_H == pytest.approx(mean_h, rel=1e-3), law
        assert r.mean_distance == pytest.approx(mean_d, abs=1e-4), law
    h = {law: r.mean_H for law, r in results.items()}
    assert h["tvd-d2"] < h["tvd-d1"] < h["lloyd-ff"] < h["lloyd"]
    table = format_s1_table(results)                 # what `swarmdeck example coverage --s1` prints
    for law, (mean_h, _) in S1_REFERENCE.items():
        assert f"| {law} | {results[law].mean_H:.5f} | {mean_h:.5f} |" in table
