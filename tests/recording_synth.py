"""Synthetic sessions for tests and benchmarks: Frames of the console's own loop on a virtual clock.

:func:`simulated_frames` runs the real :meth:`ControlLoop.tick
<swarmdeck.console.runtime.loop.ControlLoop.tick>` on simulated robots — sense,
inputs, behaviour, the one safety+actuation pipeline, send — so its Frames are
exactly what the console records: barrier diagnostics, coverage state with
cells and H, the density, contacts from a TUIO finger fed through the real
parser, operator notes as events. :func:`write_synthetic_session` records such
a run to an MCAP file (``swarmdeck sessions``/``play`` can then be tried
without running the console). :func:`retimed` builds long files cheaply.
"""
from __future__ import annotations

import dataclasses
import math
import os
from collections.abc import Iterator

from swarmdeck.console.runtime.frame import Frame

# The finger's input source: one TUIO listener (never bound: datagrams are fed to it directly).
INPUTS = {"listeners": [{"name": "table", "timeout": 0.3}]}


def simulated_frames(n_robots: int = 6, n_ticks: int = 100, dt: float = 0.033, seed: int = 0,
                     t0: float = 0.0, coverage: bool = True) -> Iterator[Frame]:
    """``n_ticks`` Frames of :meth:`ControlLoop.tick` with ``n_robots`` simulated robots (seeded by
    ``seed``), the barrier on, on a virtual clock from ``t0`` s with period ``dt`` s.

    ``coverage=True``: the coverage behaviour on the console's circling bump (frames carry cells,
    centroids and H); ``False``: rendezvous (cheaper, for long files). Every third tick a TUIO
    finger circling near the centre is fed to the loop's input source (contacts and a contact
    bump in the Frames); tick ``k`` with ``k % 50 == 25`` carries the event ``"tick k: operator note"``.
    """
    from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
    from swarmdeck.inputs import InputConfig, InputHub, InputSource
    from swarmdeck.inputs.oscbuild import cursor_sets, tuio_bundle

    config = LoopConfig(n_robots=n_robots, dt=dt, seed=seed, behaviour="coverage" if coverage else "rendezvous")
    inputs = InputConfig.from_dict(INPUTS)
    finger = InputSource(inputs.listeners[0])
    now = [t0]
    loop = ControlLoop(config, inputs=InputHub([finger], config=inputs), clock=lambda: now[0])
    try:
        for k in range(n_ticks):
            now[0] = t0 + k * dt
            if k % 50 == 25:
                loop.post(f"tick {k}: operator note")
            yield loop.tick()
            if k % 3 == 0:  # normalised surface coordinates; arrives between ticks on the loop's clock
                a = 0.5 * now[0]
                x, y = 0.5 + 0.1 * math.cos(a), 0.5 + 0.1 * math.sin(a)
                finger.feed(tuio_bundle("2Dcur", [1], cursor_sets([(1, x, y)]), fseq=k), ("10.0.0.5", 3333),
                            now[0] + 0.3 * dt)
    finally:
        loop.close()


def as_recorded(frame: Frame) -> Frame:
    """``frame`` as a recording holds it: through the recorder's codec (exact poses and commands,
    float32 nominal, derived safe command and geometry)."""
    from swarmdeck.console.recording.codec import decode_frame, encode_frame

    return decode_frame(encode_frame(frame))


def retimed(frame: Frame, tick: int, time: float) -> Frame:
    """The same frame content at another tick/time (to build long files cheaply)."""
    return dataclasses.replace(frame, tick=tick, time=time, run_time=time)


def write_synthetic_session(path: str | os.PathLike[str], n_robots: int = 6, seconds: float = 10.0,
                            dt: float = 0.033, seed: int = 0) -> int:
    """Record a simulated coverage run of ``seconds`` s to ``path``; returns the number of frames."""
    from swarmdeck.console.recording.recorder import Recorder

    n = int(round(seconds / dt))
    with Recorder(path, {"robots": list(range(n_robots)), "config": {"source": "synthetic", "seed": seed}}) as rec:
        for frame in simulated_frames(n_robots, n, dt, seed):
            rec.write_frame(frame)
    return n
