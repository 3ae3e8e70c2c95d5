"""Choosing the distributed filter: the mode switch, "auto"'s robot count, a too-short sensing radius refused."""
from __future__ import annotations

import numpy as np
import pytest

from swarmdeck.safety import BarrierConfig, SafetyFilter, UnicycleSafetyFilter
from swarmdeck.safety.scenes import arena_for, grid_scene


def test_sensing_radius_too_small_is_refused_with_the_reason() -> None:
    need = BarrierConfig().pair_bind_distance()
    with pytest.raises(ValueError, match=r"sensing_radius 0.3 m is too small.*max_speed 0.2 m/s.*gamma 100.*0\.4\d\d m"):
        BarrierConfig(mode="distributed", sensing_radius=0.3)
    with pytest.raises(ValueError, match="sensing_radius"):
        BarrierConfig(mode="auto", sensing_radius=need - 1e-3)
    # slower robots or a larger γ need less: the same radius is fine there
    BarrierConfig(mode="distributed", sensing_radius=0.3, max_speed=0.01)
    ok = BarrierConfig(mode="distributed", sensing_radius=need + 0.01)
    assert ok.neighbour_radius() == need + 0.01
    # the unicycle filter re-derives max_speed from the wheels: the check runs again
    UnicycleSafetyFilter(ok)


@pytest.mark.parametrize("kwargs", [{"mode": "decentralised"}, {"distributed_above": -1}])
def test_bad_mode_refused(kwargs) -> None:
    with pytest.raises(ValueError, match="BarrierConfig"):
        BarrierConfig(**kwargs)


def test_auto_switches_above_the_robot_count() -> None:
    rng = np.random.default_rng(1)
    cfg = BarrierConfig(mode="auto", distributed_above=40, bounds=arena_for(60, 0.2, fill=0.8))
    for n, method in ((40, {"active-set", "clarabel", "mixed"}), (41, {"distributed"})):
        x, nominal = grid_scene(n, rng, cfg, pitch=0.2)
        nominal = (x.mean(axis=0) - x) * 10  # everyone at the centre: the filter must act
        _, diag = SafetyFilter(cfg).filter(x, nominal)
        assert diag.ok and diag.method in method, (n, diag.method)
    assert BarrierConfig.from_dict({"mode": "distributed"}).mode == "distributed"
    assert BarrierConfig(mode="auto").to_dict()["distributed_above"] == BarrierConfig().distributed_above


@pytest.mark.parametrize("bad", [-1, 1.5, True, "4"])
def test_consensus_passes_must_be_a_count(bad: object) -> None:
    """``distributed_consensus_passes`` from a config file: a non-negative integer, else refused naming it."""
    with pytest.raises(ValueError, match="distributed_consensus_passes"):
        BarrierConfig.from_dict({"distributed_consensus_passes": bad})
    assert BarrierConfig.from_dict({"distributed_consensus_passes": 4}).distributed_consensus_passes == 4
    assert BarrierConfig().distributed_consensus_passes == 0
