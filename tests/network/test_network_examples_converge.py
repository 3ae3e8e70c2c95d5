"""The paper's rendezvous and formation, rewritten as decentralised controllers over a lossy network, converge:
the rendezvous spread shrinks and the formation's edge-length error falls (examples/decentralised_*.py)."""
from __future__ import annotations

from swarmdeck.devices import Arena, ArenaConfig
from swarmdeck.examples import decentralised_formation, decentralised_rendezvous


def test_decentralised_rendezvous_spread_shrinks():
    arena = Arena(6, duration=12.0, config=ArenaConfig(seed=1))
    out = decentralised_rendezvous.experiment(arena, loss=0.1, latency=1, seed=0)
    assert out["final spread (m)"] < 0.5 * out["initial spread (m)"]
    assert out["messages lost"] > 0 and out["controller errors"] == 0
    assert arena.report().validation.collision_pairs == 0


def test_decentralised_formation_error_falls():
    arena = Arena(6, duration=15.0, config=ArenaConfig(seed=1))
    out = decentralised_formation.experiment(arena, loss=0.05, seed=0)
    assert out["largest edge-length error (m)"] < 0.25 * out["initial largest edge-length error (m)"]
    assert out["controller errors"] == 0
