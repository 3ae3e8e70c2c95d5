"""A synthetic TUIO 1.1 sender: fingers circling (and pinching) on the surface,
for checking a console or a listener without a tablet
(``swarmdeck inputs send``).

Each frame is one bundle ``source alive set* fseq`` on ``/tuio/2Dcur`` with the
sender's velocities (axis lengths per second, REFERENCE.md §6); after the last
frame an empty ``alive`` with ``fseq -1`` lifts every finger, like the reference
server. UDP, or TCP with the 4-byte big-endian length prefix.
"""
from __future__ import annotations

import math
import socket
import struct
import time
from collections.abc import Callable

from . import oscbuild as ob


def demo_frame(k: int, t: float, fingers: int = 2, period: float = 8.0, radius: float = 0.25,
               source: str = "swarmdeck-demo") -> bytes:
    """Frame ``k`` at time ``t`` (s): ``fingers`` cursors on a circle of ``radius``
    (surface units) around the centre, one turn per ``period`` s; with two
    fingers they also pinch (their distance breathes between 0.3 and 1 × radius)."""
    w = 2.0 * math.pi / period
    sets = []
    for i in range(fingers):
        ph = w * t + 2.0 * math.pi * i / fingers
        r = radius * (0.65 + 0.35 * math.cos(0.5 * w * t)) if fingers == 2 else radius
        dr = -radius * 0.35 * 0.5 * w * math.sin(0.5 * w * t) if fingers == 2 else 0.0
        x = 0.5 + r * math.cos(ph)
        y = 0.5 - r * math.sin(ph)  # y down on the surface: counter-clockwise in the arena
        vx = dr * math.cos(ph) - r * w * math.sin(ph)
        vy = -(dr * math.sin(ph) + r * w * math.cos(ph))
        sets.append((i + 1, x, y, vx, vy, 0.0))
    return ob.tuio_bundle("2Dcur", [s[0] for s in sets], sets, fseq=k + 1, source=source)


def run(host: str = "127.0.0.1", port: int = 3333, *, duration: float = 10.0, rate: float = 60.0,
        fingers: int = 2, tcp: bool = False, clock: Callable[[], float] = time.monotonic,
        sleep: Callable[[float], None] = time.sleep) -> int:
    """Send ``duration`` s of demo frames at ``rate`` Hz to ``host:port``; returns
    the number of frames sent (the final lift bundle not counted)."""
    if not (rate > 0 and duration >= 0 and 1 <= fingers <= 20):
        raise ValueError(f"need rate > 0 Hz, duration >= 0 s and 1..20 fingers; got {rate}, {duration}, {fingers}")
    source = f"swarmdeck-demo@{socket.gethostname()}"
    if tcp:
        sock = socket.create_connection((host, port), timeout=5.0)
        send: Callable[[bytes], object] = lambda d: sock.sendall(struct.pack(">I", len(d)) + d)  # noqa: E731
    else:
        sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        send = lambda d: sock.sendto(d, (host, port))  # noqa: E731
    try:
        t0 = clock()
        k = 0
        while True:
            t = clock() - t0
            if t > duration:
                break
            send(demo_frame(k, t, fingers, source=source))
            k += 1
            sleep(max(0.0, t0 + k / rate - clock()))
        send(ob.tuio_bundle("2Dcur", [], [], fseq=-1, source=source))
        return k
    finally:
        sock.close()
