"""The oscsend recipe of inputs/README.md works as written, with the real liblo
`oscsend` (Debian liblo-tools; scripts/test installs it): one finger down, moved
(not a second finger, though every oscsend comes from a new port), then lifted by an
empty ALIVE. The recipe's lines are read from the README; only the port is changed."""
from __future__ import annotations

import shlex
import shutil
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest

from swarmdeck.inputs import Calibration, ListenerConfig, UdpListener

pytestmark = [
    pytest.mark.liblo,
    pytest.mark.skipif(shutil.which("oscsend") is None,
                       reason="liblo-tools (oscsend) not installed; `bash scripts/test` installs it"),
]

README = Path(__file__).resolve().parents[2] / "inputs" / "README.md"


def recipe() -> list[list[str]]:
    out = []
    for line in README.read_text().splitlines():
        line = line.strip()
        if line.startswith("oscsend 127.0.0.1 3333 "):
            out.append(shlex.split(line, comments=True))
    return out


def test_the_readme_recipe_puts_down_moves_and_lifts_one_finger():
    lines = recipe()
    assert len(lines) >= 6
    t = [0.0]
    lst = UdpListener(ListenerConfig(port=0), clock=lambda: t[0]).start()
    seen = []
    lst.on_datagram = lambda data, peer, transport, tt: seen.append(peer)
    states = []
    try:
        for k, argv in enumerate(lines):
            argv[2] = str(lst.address[1])
            subprocess.run(argv, check=True, timeout=10)
            end = time.monotonic() + 5
            while len(seen) < k + 1:  # delivery over loopback is asynchronous
                assert time.monotonic() < end, f"datagram of {argv} never arrived"
                time.sleep(0.002)
            snap = lst.poll(t[0])
            states.append([(c.id, tuple(np.round(c.position, 4))) for c in snap.contacts])
            assert not any(h.errors for h in snap.health), snap.health
    finally:
        lst.close()
    assert len({p[1] for p in seen}) == len(lines)  # every oscsend came from its own port
    cal = Calibration()
    centre = tuple(np.round(cal.to_arena(np.array([[0.5, 0.5]]))[0], 4))
    right = tuple(np.round(cal.to_arena(np.array([[0.6, 0.5]]))[0], 4))
    assert all(len(s) <= 1 for s in states)  # never a second finger
    positions = [s[0] for s in states if s]
    assert positions[0] == (1, centre) and positions[-1] == (1, right)
    assert states[-1] == []  # the empty ALIVE lifted it
