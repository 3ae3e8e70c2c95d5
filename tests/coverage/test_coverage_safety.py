"""Coverage through the safety filter where the barrier really binds: TVD-D1 still beats Lloyd.

30 robots follow one narrow bump (σ = 0.15 m, floor 0.005) orbiting the arena centre. The
density packs them ≈ 0.16 m apart at the peak, below D_s = 0.17 m, so the controller raises its
packing warning and the barrier holds robots apart all the time (about a fifth of all
robot-steps are changed). The earlier scene (16 robots on the demo density) changed 60 of
9,712 robot-steps and mean H by 7e-6: the barrier hardly took part.
"""
from __future__ import annotations

from swarmdeck.coverage import AnalyticDensity, Bump, Constant, Orbit
from swarmdeck.devices import Arena, ArenaConfig
from swarmdeck.examples.coverage import coverage_experiment

N = 30
DENSITY = AnalyticDensity(0.005, (Bump(Orbit((0.0, 0.0), 0.5, 20.0), Constant(0.15), Constant(1.0)),))


def _run(law: str):
    arena = Arena(N, config=ArenaConfig(seed=3), duration=10.0)  # safety filter on by default
    assert arena.safety is not None
    res = coverage_experiment(arena, DENSITY, law)
    return res, arena.report()


def test_tvd_d1_beats_lloyd_where_the_barrier_binds():
    lloyd, rep_l = _run("lloyd")
    tvd, rep_t = _run("tvd-d1")
    for res, rep in ((lloyd, rep_l), (tvd, rep_t)):
        assert res["failures"] == 0 and res["H"].size == rep.safety.calls
        assert any("packing" in w or "packs" in w for w in res["warnings"]), res["warnings"]
        assert rep.safety.failures == 0 and rep.invalid_commands == 0
        v = rep.validation.to_dict()
        assert v["steps_with_collision"] == 0 and v["steps_with_boundary"] == 0
        changed = rep.safety.interventions / (rep.safety.calls * N)
        assert changed >= 0.1, changed  # the barrier binds on a tenth or more of all robot-steps
    assert tvd["H"].mean() < lloyd["H"].mean()
    assert tvd["distance"].mean() < lloyd["distance"].mean()
