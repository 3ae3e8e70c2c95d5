"""The console's ``decentralised`` behaviour: rendezvous by messages only; its Frames carry the communication graph
(recorded and drawn like every Frame field), its health line counts the traffic, and the swarm gathers."""
from __future__ import annotations

import numpy as np

from swarmdeck.console.picture import picture_of
from swarmdeck.console.recording.codec import decode_frame, encode_frame
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig


def test_the_decentralised_behaviour_gathers_the_swarm_and_shows_its_network():
    loop = ControlLoop(LoopConfig(seed=3, n_robots=6, behaviour="decentralised"))
    first = loop.tick()
    frames = [loop.tick() for _ in range(300)]
    last = frames[-1]
    assert first.behaviour == "decentralised" and not last.alerts
    assert all(f.network is not None for f in frames)
    assert last.network is not None and len(last.network.links) > 0 and last.network.rate.sum() > 0
    assert "delivered" in last.health["decentralised"]
    spread = [float(np.max(np.linalg.norm(f.points - f.points.mean(axis=0), axis=1))) for f in (first, last)]
    assert spread[1] < 0.8 * spread[0]
    layer = picture_of(last).network
    assert layer is not None and layer.busy.any()
    back = decode_frame(encode_frame(last))
    assert back.network is not None and back.network.links.tolist() == last.network.links.tolist()


def test_switching_to_another_behaviour_drops_the_network_layer():
    loop = ControlLoop(LoopConfig(seed=3, n_robots=6, behaviour="decentralised"))
    loop.tick()
    assert loop.tick().network is not None
    loop.set_behaviour("rendezvous")
    assert loop.tick().network is None
