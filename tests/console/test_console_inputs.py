"""TUIO touches over a real UDP socket become contacts and a density bump in the loop's Frames."""
from __future__ import annotations

import socket
import time

import numpy as np

from swarmdeck.console.runtime.loop import ControlLoop, DensityParams, LoopConfig
from swarmdeck.inputs import InputHub, ListenerConfig, UdpListener
from swarmdeck.inputs import oscbuild as ob


def test_tuio_touch_feeds_the_density() -> None:
    listener = UdpListener(ListenerConfig(port=0)).start()
    hub = InputHub([listener])
    loop = ControlLoop(LoopConfig(seed=3, n_robots=5, density=DensityParams(moving=False)), inputs=hub,
                       clock=time.monotonic)
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        assert loop.tick().density.n_bumps == 0
        # normalised (0.75, 0.25), y down → arena (0.8, 0.5) m
        datagram = ob.tuio_bundle("2Dcur", [1], ob.cursor_sets([(1, 0.75, 0.25)]), fseq=1, source="test")
        deadline = time.monotonic() + 10
        while True:
            sock.sendto(datagram, listener.address)
            f = loop.tick()
            if len(f.contacts) and f.density.n_bumps:
                break
            assert time.monotonic() < deadline, "the touch never reached the loop"
            time.sleep(0.01)
        np.testing.assert_allclose(f.contacts.positions[0], (0.8, 0.5), atol=1e-6)
        assert f.contacts.ids.tolist() == [1]
        np.testing.assert_allclose(f.density.mu[0], (0.8, 0.5), atol=0.02)
        assert any("contacts" in v for v in f.health.values())
        # a browser bump and the touch share one density
        loop.add_bump((-1.0, -0.5))
        sock.sendto(datagram, listener.address)
        assert loop.tick().density.n_bumps == 2
    finally:
        sock.close()
        loop.close()
