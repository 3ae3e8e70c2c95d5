"""Real sockets on loopback: UdpListener and TcpListener (TUIO/TCP length framing),
with python-osc as the sender and a virtual clock for receive times."""
from __future__ import annotations

import socket
import struct
import time

import numpy as np
import pytest
from pythonosc.osc_bundle_builder import IMMEDIATELY, OscBundleBuilder
from pythonosc.osc_message_builder import OscMessageBuilder
from pythonosc.udp_client import UDPClient

from swarmdeck.inputs import Capture, InputHub, ListenerConfig, TcpListener, UdpListener
from swarmdeck.inputs import oscbuild as ob


class VirtualClock:
    def __init__(self, t: float = 100.0) -> None:
        self.t = t

    def __call__(self) -> float:
        return self.t


def wait_for(pred, timeout: float = 5.0):
    """Poll ``pred`` until it returns something truthy (delivery over loopback is
    asynchronous); fail after ``timeout`` s."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        v = pred()
        if v:
            return v
        time.sleep(0.002)
    raise AssertionError("condition not met within the deadline")


def pyosc_cursor_bundle(points, fseq, source="pyosc@127.0.0.1", at=IMMEDIATELY) -> bytes:
    b = OscBundleBuilder(at)
    def msg(*typed):
        m = OscMessageBuilder(address="/tuio/2Dcur")
        for v, t in typed:
            m.add_arg(v, t)
        b.add_content(m.build())
    msg(("source", "s"), (source, "s"))
    msg(("alive", "s"), *[(s, "i") for s, _, _ in points])
    for s, x, y in points:
        msg(("set", "s"), (s, "i"), (x, "f"), (y, "f"), (0.0, "f"), (0.0, "f"), (0.0, "f"))
    msg(("fseq", "s"), (fseq, "i"))
    return b.build().dgram


@pytest.fixture
def udp():
    clock = VirtualClock()
    lst = UdpListener(ListenerConfig(port=0), clock=clock).start()
    yield lst, clock
    lst.close()


def test_python_osc_sender_moves_contacts_through_a_real_udp_socket(udp):
    lst, clock = udp
    client = UDPClient("127.0.0.1", lst.address[1])
    client._sock.sendto(pyosc_cursor_bundle([(1, 0.5, 0.5), (2, 0.0, 1.0)], 1), ("127.0.0.1", lst.address[1]))
    snap = wait_for(lambda: (s := lst.poll(clock.t)).contacts and s)
    pos = {c.id: c.position for c in snap.contacts}
    np.testing.assert_allclose(pos[1], [0.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(pos[2], [-1.6, -1.0], atol=1e-9)
    assert all(c.first_seen == 100.0 for c in snap.contacts)
    clock.t = 101.5  # silent for 1.5 s of virtual time
    snap = lst.poll(clock.t)
    assert snap.contacts == () and ("source_lost", None) in [(e.kind, e.id) for e in snap.events]


def test_datagram_over_8_kib_is_received_whole():
    clock = VirtualClock()
    cfg = ListenerConfig(port=0, max_osc_arguments=4096, max_contacts_per_source=300, max_contacts=300)
    with UdpListener(cfg, clock=clock) as lst:
        pts = [(s, (s % 20) / 20, (s // 20) / 20, ) for s in range(260)]
        data = ob.tuio_bundle("2Dcur", [p[0] for p in pts], ob.cursor_sets(pts), fseq=3, source="big@1")
        assert len(data) > 12_000
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        sock.sendto(data, ("127.0.0.1", lst.address[1]))
        snap = wait_for(lambda: (s := lst.poll(clock.t)).contacts and s)
    assert len(snap.contacts) == 260
    (peer,) = [h for h in snap.health if h.kind == "peer"]
    assert peer.warnings == {"over_8KiB": 1}


def test_garbage_is_counted_and_the_listener_keeps_working(udp):
    lst, clock = udp
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    for junk in (b"\xff" * 7, b"#bundle\x00" + b"\x00" * 8 + struct.pack(">i", -4) + b"/a\x00\x00", b"hello wor"):
        sock.sendto(junk, ("127.0.0.1", lst.address[1]))
    sock.sendto(ob.tuio_bundle("2Dcur", [5], ob.cursor_sets([(5, 0.5, 0.5)]), fseq=1), ("127.0.0.1", lst.address[1]))
    snap = wait_for(lambda: (s := lst.poll(clock.t)).contacts and s)
    (peer,) = [h for h in snap.health if h.kind == "peer"]
    assert peer.datagrams == 4
    assert peer.errors == {"unaligned": 2, "bad_bundle": 1}
    assert "multiple of 4" in peer.last_error or "element size" in peer.last_error


def test_future_timetag_is_not_waited_for(udp):
    lst, clock = udp
    data = ob.tuio_bundle("2Dcur", [1], ob.cursor_sets([(1, 0.5, 0.5)]), fseq=1, at=time.time() + 3600)
    socket.socket(socket.AF_INET, socket.SOCK_DGRAM).sendto(data, ("127.0.0.1", lst.address[1]))
    snap = wait_for(lambda: (s := lst.poll(clock.t)).contacts and s, timeout=2.0)
    (peer,) = [h for h in snap.health if h.kind == "peer"]
    assert peer.warnings == {"future_timetag": 1}


def test_capture_hook_sees_raw_bytes_peer_transport_and_time(udp):
    lst, clock = udp
    cap = Capture()
    lst.on_datagram = cap
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    data = ob.tuio_bundle("2Dcur", [1], ob.cursor_sets([(1, 0.5, 0.5)]), fseq=1)
    sock.sendto(data, ("127.0.0.1", lst.address[1]))
    (d,) = wait_for(cap.datagrams)
    assert d.data == data and d.transport == "udp" and d.t == 100.0
    assert d.peer == f"udp://127.0.0.1:{sock.getsockname()[1]}"


def test_tcp_length_framing_split_and_coalesced_packets():
    clock = VirtualClock(5.0)
    lst = TcpListener(ListenerConfig(transport="tcp", port=0), clock=clock).start()
    try:
        frames = [ob.tuio_bundle("2Dcur", [1], ob.cursor_sets([(1, 0.1 * k, 0.5)]), fseq=k, source="tcp@1") for k in (1, 2, 3)]
        wire = b"".join(struct.pack(">I", len(f)) + f for f in frames)
        with socket.create_connection(lst.address) as c:
            c.sendall(wire[:7])          # a frame split across sends
            c.sendall(wire[7:])          # and the rest coalesced
            snap = wait_for(lambda: (s := lst.poll(clock.t)).contacts and s.contacts[0].position[0] > -0.7 and s)
        np.testing.assert_allclose(snap.contacts[0].position, [0.3 * 3.2 - 1.6, 0.0], atol=1e-6)
        assert [e.kind for e in snap.events] == ["down", "move", "move"]
        assert snap.contacts[0].source == "tcp://127.0.0.1/tcp@1"  # the sender host, not its port
        with socket.create_connection(lst.address) as c:  # a bogus length closes that connection
            c.sendall(struct.pack(">I", 0x7FFFFFFF) + b"x" * 8)
            wait_for(lambda: any(h.errors.get("bad_frame_length") for h in lst.health(clock.t)))
    finally:
        lst.close()


def test_hub_merges_two_listeners_and_port_in_use_is_a_clear_error():
    clock = VirtualClock(1.0)
    hub = InputHub([UdpListener(ListenerConfig(port=0), clock=clock),
                    UdpListener(ListenerConfig(port=0, name="second"), clock=clock)], clock=clock)
    with hub:
        socks = [s.address for s in hub.sources]
        for k, addr in enumerate(socks):  # two senders on this host, told apart by their source strings
            socket.socket(socket.AF_INET, socket.SOCK_DGRAM).sendto(ob.tuio_bundle(
                "2Dcur", [1], ob.cursor_sets([(1, 0.2 + 0.5 * k, 0.5)]), fseq=1, source=f"pad{k}"), addr)
        events = []
        def both():
            s = hub.poll()
            events.extend(s.events)
            return len(s.contacts) == 2 and s
        snap = wait_for(both)
        assert [e.kind for e in events] == ["down", "down"]
        assert len({c.source for c in snap.contacts}) == 2
        assert sum(h.kind == "peer" for h in snap.health) == 2
        with pytest.raises(OSError, match="cannot bind UDP"):
            UdpListener(ListenerConfig(port=socks[0][1])).start()


def test_polling_on_another_clock_than_the_receive_clock_is_reported(udp):
    lst, clock = udp  # receive clock reads 100 s
    snap = lst.poll(3.0)
    (h,) = [h for h in snap.health if h.kind == "listener"]
    assert h.errors == {"clock_mismatch": 1}
    assert "+97.000 s off" in h.last_error and "clock=" in h.last_error
    assert not [h for h in lst.poll(100.2).health if h.kind == "listener" and h.errors["clock_mismatch"] > 1]


def test_hub_polls_listeners_on_their_own_clock_so_timeouts_survive_a_clock_mix_up(udp):
    lst, clock = udp  # receive clock at 100 s; the caller's loop clock starts at 0
    hub = InputHub([lst])
    socket.socket(socket.AF_INET, socket.SOCK_DGRAM).sendto(
        ob.tuio_bundle("2Dcur", [1], ob.cursor_sets([(1, 0.5, 0.5)]), fseq=1), lst.address)
    wait_for(lambda: hub.poll(0.0).contacts)
    clock.t = 101.2  # the tablet went silent 1.2 s ago on the receive clock
    snap = hub.poll(0.033)
    assert snap.contacts == () and ("source_lost", None) in [(e.kind, e.id) for e in snap.events]
    assert not [h for h in snap.health if h.errors.get("clock_mismatch")]  # none via the hub
