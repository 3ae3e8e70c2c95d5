"""Rendezvous with a tunable gain: a script a parameter sweep can drive (docs/sweeps.md).

It declares its parameters with defaults (``params``): run alone it uses them, and ``swarmdeck sweep`` runs it
with other values. It reports the cluster's radius as it goes and the time it first came within ``goal``
(``record_metrics``; ``time_to_goal`` fills the table's column of that name)::

    python examples/sweep_gain.py                       # the defaults
    swarmdeck run examples/sweep_gain.py --param gain=0.05  # one other value
    swarmdeck sweep examples/sweep_gain.py --param gain=0.02:0.2:4 --robots 10,20 --seeds 5 --duration 20 -o sweep-out
"""
import numpy as np

from swarmdeck.core.graphs import cycle_laplacian
from swarmdeck.coverage.group import consensus
from swarmdeck.devices import Arena, params, record_metrics

p = params(gain=0.1, goal=0.4)


def experiment(arena: Arena) -> None:
    """Consensus on the cycle graph at ``gain`` (1/s), until the arena's duration is over."""
    laplacian = cycle_laplacian(arena.n)
    reached = False
    end = arena.duration if arena.duration is not None else 20.0
    while arena.time < end - 1e-9:
        x = arena.positions()
        u = p.gain * consensus(x, laplacian)
        peak = np.linalg.norm(u, axis=1).max()
        arena.set_velocities(u * min(1.0, arena.params.max_speed / max(peak, 1e-12)))
        radius = float(np.max(np.linalg.norm(x - x.mean(axis=0), axis=1)))
        record_metrics(radius=radius)
        if not reached and radius < p.goal:
            reached = True
            record_metrics(time_to_goal=arena.time)
        arena.step()


if __name__ == "__main__":  # run alone: 6 robots (a runner's Arena() gets its --robots)
    experiment(Arena())
