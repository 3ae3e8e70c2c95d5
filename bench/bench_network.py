"""Benchmark of the information-exchange network (issue 28 item 2): its cost per control tick at N robots with
all-to-neighbour messaging.

Run: ``.venv/bin/python bench/bench_network.py [--n 100] [--ticks 300]``.

Scene: N robots uniformly at random in the 3.2 × 2.0 m arena, moving by a random walk of 5 mm per tick (so the
proximity topologies change). Every tick every robot broadcasts its position (a float64 array (2,), 30 bytes
encoded) to all its neighbours, the network steps at the new positions, and every robot reads its inbox. Per tick,
CPU time of this thread (``time.thread_time``) of

* **send**: the N broadcasts (payload checked and encoded once per broadcast);
* **step**: ``Network.step`` — topology (k-d tree), bandwidth, loss, latency, the inboxes, the traffic;
* **read**: the N ``inbox(i)`` calls (each message decoded into a fresh copy);
* **views**: the decentralised runner's per-robot part besides the network (``RobotView`` and ``Outbox`` for each
  robot, the controller call with a trivial controller that broadcasts, the outbox handed to the network) —
  ``Decentralised.step`` without the arena's step, whose cost (the barrier) every run pays anyway;

and the total against the control period (33 ms). Medians and worst over the ticks (the first 5 left out).
"""
from __future__ import annotations

import argparse

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads
import numpy as np  # noqa: E402

from swarmdeck.core.bounds import DEFAULT_BOUNDS  # noqa: E402
from swarmdeck.core.constants import CONTROL_PERIOD  # noqa: E402
from swarmdeck.network import (  # noqa: E402
    DiskTopology,
    GilbertElliottLoss,
    KNearestTopology,
    Network,
    NetworkConfig,
    Outbox,
    RobotView,
)

CONFIGS = {
    "Δ-disk 0.5 m, lossless, latency 1": NetworkConfig(topology=DiskTopology(0.5), latency=1, seed=0),
    "Δ-disk 0.5 m, Gilbert–Elliott, jitter 2, 2 kB/tick": NetworkConfig(
        topology=DiskTopology(0.5), latency=1, jitter=2, loss=GilbertElliottLoss(0.05, 0.25, 0.01, 0.9),
        bandwidth=2048, seed=0),
    "6 nearest, lossless, latency 0": NetworkConfig(topology=KNearestTopology(6), seed=0),
}


def _controller(i: int, view: RobotView) -> np.ndarray:
    view.broadcast(view.position)
    return np.zeros(2)


def _send_all(net: Network, pos: np.ndarray) -> None:
    for i in range(net.n):
        net.broadcast(i, pos[i])


def _read_all(net: Network) -> None:
    for i in range(net.n):
        net.inbox(i)


def _views(net: Network, scratch: Network, pos: np.ndarray, tick: int, config: NetworkConfig) -> None:
    """Decentralised.step's per-robot part (views, controllers, outboxes) into a scratch network."""
    n = net.n
    poses = np.column_stack((pos, np.zeros(n)))
    boxes = []
    for i in range(n):
        nb = net.neighbours(i)
        box = Outbox(i, n, config.max_message_bytes, config.max_messages_per_tick, len(nb))
        _controller(i, RobotView(i, poses[i], 0.0, tick, (), None, {}, nb, box))
        boxes.append(box)
    for box in boxes:
        for j, data in box.messages:
            if j is None:
                scratch.broadcast_encoded(box.i, data)
            else:
                scratch.send_encoded(box.i, j, data)


def run(n: int, ticks: int, config: NetworkConfig) -> tuple[dict[str, harness.Timing], float]:
    rng = np.random.default_rng(1)
    b = DEFAULT_BOUNDS
    pos = np.column_stack((rng.uniform(b.x_min, b.x_max, n), rng.uniform(b.y_min, b.y_max, n)))
    net = Network(n, config, positions=pos)
    samples: dict[str, list[float]] = {"send": [], "step": [], "read": [], "views": []}
    links = []
    for tick in range(ticks):
        t_send, _ = harness.timed(_send_all, net, pos, clock="thread")
        pos = b.clip(pos + rng.normal(scale=0.005, size=pos.shape))
        t_step, _ = harness.timed(net.step, pos, clock="thread")
        t_read, _ = harness.timed(_read_all, net, clock="thread")
        t_views, _ = harness.timed(_views, net, Network(n, config, positions=pos), pos, tick, config, clock="thread")
        if tick >= 5:
            for key, t in (("send", t_send), ("step", t_step), ("read", t_read), ("views", t_views)):
                samples[key].append(t)
            links.append(len(net.links))
    out = {k: harness.timing(v, "thread") for k, v in samples.items()}
    out["total"] = harness.timing([sum(x) for x in zip(*samples.values())], "thread")
    return out, float(np.mean(links)) / n


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, nargs="+", default=[100])
    parser.add_argument("--ticks", type=int, default=300)
    args = parser.parse_args()
    print(harness.machine())
    print(f"baseline (sort 10⁵ floats ×10): {harness.baseline().ms()} ms")
    print(harness.table_header(["network", "N", "links per robot", "send ms", "step ms", "read ms", "views ms",
                                "total ms median (worst)", "total / tick"]))
    for n in args.n:
        for name, config in CONFIGS.items():
            t, per_robot = run(n, args.ticks, config)
            print(harness.table_row(name, n, f"{per_robot:.1f}", f"{t['send'].median_ms:.3f}",
                                    f"{t['step'].median_ms:.3f}", f"{t['read'].median_ms:.3f}",
                                    f"{t['views'].median_ms:.3f}", t["total"],
                                    f"{100 * t['total'].median / CONTROL_PERIOD:.1f} %"), flush=True)


if __name__ == "__main__":
    main()
