"""Rendezvous on the cycle graph (paper §V-A).

Every robot moves toward its two neighbours on a cycle, ẋ_i = Σ_j (x_j − x_i):
without obstacles the swarm gathers at the centroid of its starting
positions. The safety barrier keeps the robots D_s apart, so they end as a
tight cluster instead of a point. The barrier's pair constraints push both
robots of a pair equally, so with one common speed scale for the whole swarm
the cluster still forms around the initial centroid (the report gives the
cluster radius and the centroid's drift).

    swarmdeck run examples/rendezvous.py --robots 6 --duration 30
"""
import numpy as np

from swarmdeck.core.graphs import cycle_laplacian
from swarmdeck.coverage.group import consensus
from swarmdeck.devices import Arena


def experiment(arena: Arena) -> dict:
    """Drive ``arena`` to rendezvous until its duration (or 30 s) is over; return the final errors."""
    laplacian = cycle_laplacian(arena.n)
    start_centroid = arena.positions().mean(axis=0)
    end = arena.duration if arena.duration is not None else 30.0
    while arena.time < end - 1e-9:
        p = arena.positions()
        u = consensus(p, laplacian)
        # One common scale for the whole swarm keeps Σ u_i = 0, so the centroid stays put
        # (saturating each robot on its own would move it).
        peak = np.linalg.norm(u, axis=1).max()
        arena.set_velocities(u * min(1.0, 0.5 * arena.params.max_speed / max(peak, 1e-12)))
        arena.step()
    p = arena.positions()
    centre = p.mean(axis=0)
    return {
        "cluster radius (m)": float(np.max(np.linalg.norm(p - centre, axis=1))),
        "centroid drift (m)": float(np.linalg.norm(centre - start_centroid)),
    }


if __name__ == "__main__":
    arena = Arena(6, duration=30.0)
    results = experiment(arena)
    arena.call_at_scripts_end()
    for name, value in results.items():
        print(f"{name}: {value:.4f}")
