"""Benchmark of decentralised isolation (issue 28.2): what running each robot's controller in its own process costs
per control tick, against the same controllers in one process.

Run: ``.venv/bin/python bench/bench_decentralised_isolation.py [--n 5 20] [--ticks 200]``.

Scene: N robots in a row, a 2-nearest network, every robot's controller broadcasts its position and returns a small
velocity (a trivial controller: what is measured is the machinery). Per tick, wall time of
``RobotControllers.decide`` (``time.perf_counter``: the workers run in other processes), median and worst over the
ticks (the first 5 left out): *in process* (the in-process seal only), *isolated* (``isolate()``: one forked worker per
robot, one pickled request and answer per robot per tick over a pipe). The network step is the same in both and not
counted.
"""
from __future__ import annotations

import argparse

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads
import numpy as np  # noqa: E402

from swarmdeck.core.constants import CONTROL_PERIOD  # noqa: E402
from swarmdeck.devices.decentralised import RobotControllers  # noqa: E402
from swarmdeck.network import KNearestTopology, NetworkConfig, RobotView  # noqa: E402


def _controller(i: int, view: RobotView) -> np.ndarray:
    view.broadcast(view.position)
    return np.array([0.01, 0.0])


def run(n: int, ticks: int, isolated: bool) -> harness.Timing:
    poses = np.column_stack((np.linspace(-1.4, 1.4, n), np.zeros(n), np.zeros(n)))
    robots = RobotControllers(n, _controller, NetworkConfig(topology=KNearestTopology(2)), positions=poses[:, :2])
    if isolated:
        robots.isolate()
    samples = []
    try:
        for tick in range(ticks):
            t, _ = harness.timed(robots.decide, poses, tick * CONTROL_PERIOD, clock="wall")
            robots.network.step(poses[:, :2])
            if tick >= 5:
                samples.append(t)
    finally:
        robots.close()
    return harness.timing(samples)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, nargs="+", default=[5, 20])
    parser.add_argument("--ticks", type=int, default=200)
    args = parser.parse_args()
    print(harness.machine())
    print(f"baseline (sort 10⁵ floats ×10): {harness.baseline().ms()} ms")
    print(harness.table_header(["controllers", "N", "decide ms median (worst)", "per robot µs", "decide / tick"]))
    for n in args.n:
        for name, isolated in (("in process", False), ("isolated (a process per robot)", True)):
            t = run(n, args.ticks, isolated)
            print(harness.table_row(name, n, t, f"{1e6 * t.median / n:.0f}",
                                    f"{100 * t.median / CONTROL_PERIOD:.1f} %"), flush=True)


if __name__ == "__main__":
    main()
