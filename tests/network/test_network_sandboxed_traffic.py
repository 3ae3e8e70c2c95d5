"""A sandboxed decentralised script's traffic reaches the trusted side (a ``network`` message before each tick's
commands): the portal's loop puts it in its Frames — live view, recording — as the script's own account, checked
like everything the child sends (a malformed one is a protocol error naming what was wrong)."""
from __future__ import annotations

import numpy as np
import pytest

from swarmdeck.console.portal.runner import SandboxCommands
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.console.sandbox.plant import SandboxPlant
from swarmdeck.console.sandbox.protocol import ProtocolError, network_traffic, pack
from swarmdeck.console.sandbox.run import run_sandboxed
from swarmdeck.examples import decentralised_rendezvous


def test_the_portal_loop_shows_a_sandboxed_scripts_network():
    frames = []

    def make_plant(n, initial):
        loop = ControlLoop(LoopConfig(n_robots=n, seed=1))
        commands = SandboxCommands()
        loop.use_behaviour(commands)
        loop.subscribe(frames.append)
        loop.pause()
        loop.tick()
        loop.run()
        return SandboxPlant.on_loop(loop, commands, 1.0, None)

    out = run_sandboxed(decentralised_rendezvous.__file__, make_plant, n_robots=4, duration=1.0)
    assert out.ok, out.error
    shown = [f.network for f in frames if f.network is not None]
    assert len(shown) >= out.ticks - 2 > 20
    assert all(net.links.shape == (8, 2) for net in shown)  # the cycle on 4 robots, both ways
    assert sum(float(net.rate.sum()) for net in shown) > 0


@pytest.mark.parametrize(("message", "words"), [
    ({"t": "network", "links": b"\0" * 15, "rate": b""}, "float64 pairs"),
    ({"t": "network", "links": pack(np.array([[0.0, 7.0]])), "rate": pack(np.array([1.0]))}, "robot indices 0..3"),
    ({"t": "network", "links": pack(np.array([[0.0, 1.5]])), "rate": pack(np.array([1.0]))}, "robot indices"),
    ({"t": "network", "links": pack(np.array([[0.0, 1.0]])), "rate": pack(np.array([np.nan]))}, "finite"),
    ({"t": "network", "links": pack(np.array([[0.0, 1.0]])), "rate": b"x"}, "'rate' has 1 bytes"),
    ({"t": "network", "links": pack(np.zeros((20_001, 2))), "rate": pack(np.zeros(20_001))}, "at most 20000"),
])
def test_a_malformed_network_message_is_a_protocol_error(message, words):
    with pytest.raises(ProtocolError, match=words):
        network_traffic(message, 4)
    links, rate = network_traffic({"t": "network", "links": pack(np.array([[0.0, 1.0], [3.0, 2.0]])),
                                   "rate": pack(np.array([30.0, 0.0]))}, 4)
    assert links.tolist() == [[0, 1], [3, 2]] and rate.tolist() == [30.0, 0.0]
