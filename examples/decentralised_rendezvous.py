"""Rendezvous with messages only: each robot knows its own pose and what its cycle neighbours told it.

The paper's rendezvous (§V-A), ẋ_i = Σ_j (x_j − x_i) over the cycle graph G, rewritten in the decentralised
style: every tick each robot broadcasts its look-ahead point over the network (the cycle G as a fixed topology,
one tick of latency, 10 % Bernoulli loss) and moves toward the last positions its neighbours sent, saturated on
its own. No robot ever reads another's pose: `swarmdeck.devices.decentralised` refuses it. The spread (largest
distance from the swarm's centroid) shrinks until the safety barrier holds the robots D_s apart.

    swarmdeck run examples/decentralised_rendezvous.py --robots 6 --duration 30
    swarmdeck example decentralised-rendezvous
"""
import numpy as np

from swarmdeck.core.graphs import cycle_laplacian
from swarmdeck.core.kinematics import lookahead_points, saturate
from swarmdeck.devices import Arena
from swarmdeck.devices.decentralised import Decentralised
from swarmdeck.network import BernoulliLoss, FixedTopology, NetworkConfig, RobotView


def make_robot(ell: float, speed: float):
    """The controller every robot runs: ``robot(i, view) -> (2,)`` m/s."""

    def robot(i: int, view: RobotView) -> np.ndarray:
        me = lookahead_points(view.pose[None], ell)[0]
        heard = view.state.setdefault("heard", {})  # sender -> last position it sent
        for message in view.inbox:
            heard[message.sender] = np.asarray(message.payload["p"], dtype=float)
        view.broadcast({"p": me})
        if not heard:
            return np.zeros(2)
        u = sum((p - me for p in heard.values()), np.zeros(2))
        return saturate(u[None], speed)[0]

    return robot


def spread(positions: np.ndarray) -> float:
    """Largest distance from the centroid, m (computed outside the controllers, by the experimenter)."""
    return float(np.max(np.linalg.norm(positions - positions.mean(axis=0), axis=1)))


def experiment(arena: Arena, loss: float = 0.1, latency: int = 1, seed: int = 0) -> dict:
    """Run decentralised rendezvous until the arena's duration (or 30 s); return the spread and the traffic."""
    config = NetworkConfig(topology=FixedTopology.from_laplacian(cycle_laplacian(arena.n)), latency=latency,
                           loss=BernoulliLoss(loss) if loss > 0 else None, seed=seed)
    run = Decentralised(arena, make_robot(arena.ell, 0.5 * arena.params.max_speed), config)
    start = spread(arena.positions())
    end = arena.duration if arena.duration is not None else 30.0
    while arena.time < end - 1e-9:
        run.step()
    stats = run.network.stats
    return {"initial spread (m)": start, "final spread (m)": spread(arena.positions()),
            "messages delivered": int(stats["delivered"]), "messages lost": int(stats["lost"]),
            "controller errors": int(sum(run.errors.values()))}


if __name__ == "__main__":
    arena = Arena()  # `swarmdeck run --robots N --duration S` sets them; 6 robots, 30 s otherwise
    results = experiment(arena)
    arena.call_at_scripts_end()
    for name, value in results.items():
        print(f"{name}: {value:.4f}" if isinstance(value, float) else f"{name}: {value}")
