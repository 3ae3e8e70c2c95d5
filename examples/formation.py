"""Formation control of six robots on a rigid graph (paper §V-B).

Each edge (i, j) of a minimally rigid graph pulls or pushes its two robots
toward the desired distance d_ij, by gradient descent on the edge tension
w_ij = α/4 (‖x_i − x_j‖² − d_ij²)². Rigidity fixes the shape — here a regular
hexagon with 0.4 m sides — up to rotation, translation and reflection.

    swarmdeck run examples/formation.py --duration 40
"""
import numpy as np

from swarmdeck.core.graphs import rigid_formation
from swarmdeck.coverage.group import formation_control, formation_errors
from swarmdeck.devices import Arena, saturate


def experiment(arena: Arena, edge_length: float = 0.4, alpha: float = 4.0) -> dict:
    """Form a regular polygon of ``arena.n`` robots; return the final edge-length errors."""
    _, edges, distances = rigid_formation(arena.n, edge_length)
    # Give the polygon's corners to the robots in their angular order around the swarm's
    # centre, so nobody has to pass through anybody else (the barrier would not let them).
    p0 = arena.positions() - arena.positions().mean(axis=0)
    order = np.argsort(np.arctan2(p0[:, 1], p0[:, 0]))
    edges = order[edges]
    end = arena.duration if arena.duration is not None else 40.0
    while arena.time < end - 1e-9:
        p = arena.positions()
        arena.set_velocities(saturate(formation_control(p, edges, distances, alpha), arena.params.max_speed))
        arena.step()
    errors = formation_errors(arena.positions(), edges, distances)
    return {"largest edge-length error (m)": float(errors.max()), "mean edge-length error (m)": float(errors.mean())}


if __name__ == "__main__":
    arena = Arena(6, duration=40.0)
    results = experiment(arena)
    arena.call_at_scripts_end()
    for name, value in results.items():
        print(f"{name}: {value:.4f}")
