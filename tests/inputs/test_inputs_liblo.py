"""Cross-implementation: Debian liblo-tools (`oscsend`, `oscsendfile`) send into
the real UDP listener. scripts/test installs liblo-tools when missing."""
from __future__ import annotations

import shutil
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest

from swarmdeck.inputs import Calibration, ListenerConfig, UdpListener

pytestmark = [
    pytest.mark.liblo,
    pytest.mark.skipif(shutil.which("oscsend") is None or shutil.which("oscsendfile") is None,
                       reason="liblo-tools (oscsend, oscsendfile) not installed; `bash scripts/test` installs it"),
]

DUMP = Path(__file__).resolve().parents[1] / "data" / "inputs" / "tuio_two_fingers.oscdump"
CAL = Calibration()


class VirtualClock:
    def __init__(self) -> None:
        self.t = 0.0

    def __call__(self) -> float:
        return self.t


def wait_for(pred, timeout=5.0):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        v = pred()
        if v:
            return v
        time.sleep(0.005)
    raise AssertionError("condition not met within the deadline")


@pytest.fixture
def listener():
    clock = VirtualClock()
    lst = UdpListener(ListenerConfig(port=0), clock=clock).start()
    yield lst, clock
    lst.close()


def test_oscsend_single_messages_make_a_contact(listener):
    lst, clock = listener
    port = str(lst.address[1])
    for args in (["ss", "source", "oscsend@127.0.0.1"], ["si", "alive", "3"],
                 ["sifffff", "set", "3", "0.25", "0.75", "0", "0", "0"], ["si", "fseq", "1"]):
        subprocess.run(["oscsend", "127.0.0.1", port, "/tuio/2Dcur", *args], check=True, timeout=10)
    snap = wait_for(lambda: (s := lst.poll(clock.t)).contacts and s)
    (c,) = snap.contacts
    # each oscsend is its own datagram from its own (ephemeral) port; state is kept
    # per sending host and source string, so the four make one frame of one finger
    assert c.id == 3 and c.kind == "cursor"
    np.testing.assert_allclose(c.position, CAL.to_arena(np.array([[0.25, 0.75]]))[0], atol=1e-6)
    assert not any(h.errors for h in snap.health)


def test_oscsendfile_replays_a_committed_dump_as_bundles_into_the_listener(listener):
    """The dump (oscdump's text format: `<hex sec>.<hex frac> <address> <types> <args>`;
    lines sharing a stamp become one bundle) holds 6 frames of two moving fingers
    50 ms apart and a final empty frame with fseq -1; replayed at 4× speed."""
    lst, clock = listener
    seen = []
    lst.on_datagram = lambda data, peer, transport, t: seen.append(data)
    subprocess.run(["oscsendfile", "127.0.0.1", str(lst.address[1]), str(DUMP), "4"], check=True, timeout=20)
    wait_for(lambda: len(seen) == 7)
    snap = lst.poll(clock.t)
    assert all(d.startswith(b"#bundle\x00") for d in seen)
    kinds = [(e.kind, e.id) for e in snap.events]
    assert kinds[:2] == [("down", 7), ("down", 8)]
    assert kinds.count(("move", 7)) == 5 and kinds.count(("move", 8)) == 5
    assert kinds[-2:] == [("up", 7), ("up", 8)]
    last = {e.id: e.contact for e in snap.events if e.kind == "up"}
    np.testing.assert_allclose(last[7].position, CAL.to_arena(np.array([[0.7, 0.5]]))[0], atol=1e-5)
    np.testing.assert_allclose(last[8].position, CAL.to_arena(np.array([[0.5, 0.5]]))[0], atol=1e-5)
    np.testing.assert_allclose(last[7].velocity, [2.0 * 3.2, 0.0], atol=1e-5)  # sender's X = 2 axis/s
    assert last[7].source.endswith("/liblo-test@127.0.0.1")
    (h,) = [h for h in snap.health if h.kind == "tuio"]
    assert h.datagrams == 7 and not h.errors and not h.warnings
