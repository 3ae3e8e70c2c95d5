"""Synthetic sessions: Frames of a real simulated coverage run, for tests, benchmarks and demos.

:func:`simulated_frames` drives the simulated arena (``swarmdeck.devices``) with
the coverage controller (``swarmdeck.coverage``) on a virtual clock and yields one
:class:`Frame` per tick, filled the way the console loop fills it (poses,
nominal and sent commands, coverage state with cells and H, density, events).
:func:`write_synthetic_session` records such a run to an MCAP file
(``swarmdeck sessions``/``play`` can then be tried without running the console).
"""
from __future__ import annotations

import dataclasses
import os
from collections.abc import Iterator

import numpy as np

from swarmdeck.console.runtime.frame import BarrierFrame, ContactsFrame, CoverageFrame, Frame


def simulated_frames(n_robots: int = 6, n_ticks: int = 100, dt: float = 0.033, seed: int = 0,
                     t0: float = 0.0, coverage: bool = True) -> Iterator[Frame]:
    """``n_ticks`` Frames of a coverage run of ``n_robots`` robots (virtual clock from ``t0`` s, period ``dt``).

    With ``coverage=False`` the robots rotate in place-ish (cheap, for long synthetic files).
    """
    from swarmdeck.coverage import GaussianMixture
    from swarmdeck.coverage.controller import CoverageConfig, CoverageController
    from swarmdeck.core.kinematics import lookahead_points, si_to_unicycle
    from swarmdeck.devices.simulator import ArenaConfig, SimulatedArena

    ell = 0.03
    bounds = (-1.6, 1.6, -1.0, 1.0)
    sim = SimulatedArena(n_robots=n_robots, config=ArenaConfig(bounds=bounds, dt=dt, seed=seed))
    density = GaussianMixture(floor=0.05, mu=np.array([[0.5, 0.2], [-0.6, -0.3]]), sigma=np.array([0.3, 0.25]),
                              weight=np.array([1.0, 0.7]))
    ctrl = CoverageController(CoverageConfig(bounds=bounds), density) if coverage else None
    ids = np.arange(n_robots)
    rng = np.random.default_rng(seed)
    for k in range(n_ticks):
        poses = sim.poses
        t = t0 + k * dt
        if ctrl is not None:
            nominal, state = ctrl(lookahead_points(poses, ell), k * dt)
            cov = CoverageFrame.from_state(state)
        else:
            nominal = 0.05 * rng.standard_normal((n_robots, 2))
            cov = None
        safe = nominal
        v, w = si_to_unicycle(poses, safe, ell)
        events = (f"tick {k}: operator note",) if k % 50 == 25 else ()
        contacts = ContactsFrame(sources=("tuio:sim",), ids=[1], positions=[[0.1 * np.cos(t), 0.1 * np.sin(t)]],
                                 velocities=[[0.0, 0.0]]) if k % 3 == 0 else ContactsFrame()
        yield Frame(tick=k, time=t, run_time=k * dt, dt=dt, poses=poses, ids=ids, nominal=nominal, safe=safe,
                    v=v, w=w, bounds=bounds, lookahead=ell,
                    barrier=BarrierFrame(enabled=False, intervention=np.zeros(n_robots)),
                    coverage=cov, density=density if coverage else None, contacts=contacts,
                    behaviour="coverage", params={"kappa": 1.0, "law": "tvd-d1"}, events=events,
                    health={"simulator": "ok"}, timing={"total": 0.001})
        sim.step(v, w)


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
