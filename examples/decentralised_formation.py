"""Formation control with messages only: each robot knows its own pose and what its graph neighbours sent.

The paper's formation control (§V-B) on a minimally rigid graph, rewritten in the decentralised style: robot i
knows its edges and their desired lengths d_ij (its program), broadcasts its look-ahead point every tick
over the network (the rigid graph as a fixed topology, one tick of latency, 5 % Bernoulli loss) and descends
the edge tensions with the last positions its neighbours sent:
u_i = α Σ_j (‖x_i − x_j‖² − d_ij²)(x_j − x_i), saturated on its own. The formation error falls.

    swarmdeck run examples/decentralised_formation.py --robots 6 --duration 40
    swarmdeck example decentralised-formation
"""
import numpy as np

from swarmdeck.core.graphs import rigid_formation
from swarmdeck.core.kinematics import lookahead_points, saturate
from swarmdeck.coverage.group import formation_errors
from swarmdeck.devices import Arena
from swarmdeck.devices.decentralised import Decentralised
from swarmdeck.network import BernoulliLoss, FixedTopology, NetworkConfig, RobotView


def make_robot(targets: list[dict[int, float]], ell: float, alpha: float, speed: float):
    """The controller: robot i's desired distances ``targets[i]`` (neighbour -> d_ij, m) are its program."""

    def robot(i: int, view: RobotView) -> np.ndarray:
        me = lookahead_points(view.pose[None], ell)[0]
        heard = view.state.setdefault("heard", {})
        for message in view.inbox:
            heard[message.sender] = np.asarray(message.payload, dtype=float)
        view.broadcast(me)
        u = np.zeros(2)
        for j, d in targets[i].items():
            if j in heard:
                diff = heard[j] - me
                u += alpha * (diff @ diff - d * d) * diff
        return saturate(u[None], speed)[0]

    return robot


def experiment(arena: Arena, edge_length: float = 0.4, alpha: float = 4.0, loss: float = 0.05, seed: int = 0) -> dict:
    """Form a regular polygon of ``arena.n`` robots by messages; return the edge-length errors."""
    _, edges, distances = rigid_formation(arena.n, edge_length)
    # The experimenter hands out the corners once, before the run (as the centralised example does), in the
    # robots' angular order around the swarm's centre; from then on each robot knows only its own edges.
    p0 = arena.positions() - arena.positions().mean(axis=0)
    edges = np.argsort(np.arctan2(p0[:, 1], p0[:, 0]))[edges]
    targets: list[dict[int, float]] = [{} for _ in range(arena.n)]
    for (a, b), d in zip(edges.tolist(), distances.tolist()):
        targets[a][b] = targets[b][a] = d
    config = NetworkConfig(topology=FixedTopology.from_edges(edges), latency=1,
                           loss=BernoulliLoss(loss) if loss > 0 else None, seed=seed)
    run = Decentralised(arena, make_robot(targets, arena.ell, alpha, arena.params.max_speed), config)
    start = formation_errors(arena.positions(), edges, distances)
    end = arena.duration if arena.duration is not None else 40.0
    while arena.time < end - 1e-9:
        run.step()
    errors = formation_errors(arena.positions(), edges, distances)
    return {"initial largest edge-length error (m)": float(start.max()),
            "largest edge-length error (m)": float(errors.max()), "mean edge-length error (m)": float(errors.mean()),
            "messages delivered": int(run.network.stats["delivered"]),
            "controller errors": int(sum(run.errors.values()))}


if __name__ == "__main__":
    arena = Arena()  # `swarmdeck run --robots N --duration S` sets them; 6 robots, 40 s otherwise
    results = experiment(arena)
    arena.call_at_scripts_end()
    for name, value in results.items():
        print(f"{name}: {value:.4f}" if isinstance(value, float) else f"{name}: {value}")
