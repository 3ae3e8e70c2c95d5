"""The console's ``decentralised`` behaviour: rendezvous by messages only, with the communication graph in the Frame.

Each robot runs the controller of ``examples/decentralised_rendezvous.py`` (it broadcasts its look-ahead point and
moves toward the last points its neighbours sent, saturated on its own) over a Δ-disk network
(:data:`DEFAULT_NETWORK`: Δ = 1.5 m, one tick of latency, 10 % Bernoulli loss, seeded), through
:class:`~swarmdeck.devices.decentralised.RobotControllers` — the same isolation as ``Decentralised`` on an Arena: a
controller sees only its own view. The network is stepped at the tick's positions after the controllers ran; the
Frame's ``network`` (:meth:`DecentralisedRendezvous.network_frame`) shows the links and their traffic, drawn as the
console's **network** layer. Robots with no neighbour in range stay where they are.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from swarmdeck.console.runtime.behaviours import TickInput
from swarmdeck.console.runtime.network_frame import NetworkFrame
from swarmdeck.console.runtime.params import BehaviourParams
from swarmdeck.devices.decentralised import RobotControllers
from swarmdeck.examples.decentralised_rendezvous import make_robot
from swarmdeck.network import BernoulliLoss, DiskTopology, NetworkConfig

__all__ = ["DEFAULT_NETWORK", "DecentralisedRendezvous"]

#: The console's network for the decentralised behaviour.
DEFAULT_NETWORK = NetworkConfig(topology=DiskTopology(1.5), latency=1, loss=BernoulliLoss(0.1), seed=0)


class DecentralisedRendezvous:
    """Behaviour ``decentralised`` (module docstring); ``config``: its network."""

    name = "decentralised"

    def __init__(self, params: BehaviourParams, config: NetworkConfig = DEFAULT_NETWORK) -> None:
        self.speed_share = min(1.0, 0.5 * params.gain)  # of the loop's speed limit
        self.config = config
        self.robots: RobotControllers | None = None

    def __call__(self, tick: TickInput) -> tuple[NDArray[np.float64], None]:
        poses, points = np.asarray(tick.poses, dtype=float), np.asarray(tick.points, dtype=float)
        n = len(poses)
        if self.robots is None or self.robots.n != n:  # first tick, or the robots changed: a fresh network
            ell = float(np.linalg.norm(points[0] - poses[0, :2])) if n else 0.0
            controller = make_robot(ell, self.speed_share * float(tick.max_speed))
            self.robots = RobotControllers(n, controller, self.config, positions=poses[:, :2])
        u = self.robots.decide(poses, float(tick.t))
        self.robots.network.step(poses[:, :2])
        return u, None

    def network_frame(self, dt: float) -> NetworkFrame | None:
        """This tick's links and messages per second over each (``dt``: the tick, s)."""
        if self.robots is None:
            return None
        traffic = self.robots.network.traffic()
        return NetworkFrame.from_traffic(traffic.links, traffic.messages, dt)

    def health(self) -> str:
        """Messages delivered and lost, controller errors."""
        if self.robots is None:
            return "network: not started"
        st = self.robots.network.stats
        return (f"network: {st['delivered']} delivered, {st['lost']} lost, "
                f"{sum(self.robots.errors.values())} controller errors")
