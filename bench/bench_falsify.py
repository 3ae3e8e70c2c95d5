"""Benchmark: runs the falsifier needs to find the near-miss fixture's contact vs uniform sampling (issue 31).

Run: ``.venv/bin/python bench/bench_falsify.py [--seeds 20] [--budget 300] [--uniform-cap 20000] [--jailed 3]``
(prints markdown tables for bench/RESULTS.md).

The fixture is examples/near_miss.py: two robots pass 75 mm clear unless their set-up errors (within 2 cm, 5°)
line up in one corner of the tolerance. For each seed:

* **cross-entropy** (:func:`~swarmdeck.console.sandbox.falsify.cross_entropy`, the falsifier's search): runs until
  the first contact, each run the verification plant in this process (tests/falsify_fixtures.py: the simulator
  under ``VerificationRobots`` — tracking noise, latency, drops, the contact model — without the jail);
* **uniform**: candidates drawn uniformly from the same search space, in order, until the first contact. Uniform
  needs thousands of runs, so its runs are the fixture's closed form (both robots drive straight at a constant
  speed: the minimum clearance of two straight constant-velocity paths, checked against the plant on
  ``--check`` candidates below) — and :func:`~swarmdeck.console.sandbox.falsify.uniform_search` draws them.

``--jailed K``: the falsifier through ``falsify_script`` with jailed runs (a serial executor) for the first K
seeds, the runs until its first contact (the same search, the real sandbox).
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads
import numpy as np
from numpy.typing import NDArray

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from falsify_fixtures import (  # noqa: E402
    NEAR_MISS_DURATION,
    NEAR_MISS_SPACE,
    NEAR_MISS_SPEED,
    NEAR_MISS_START,
    near_miss_objective,
    near_miss_run,
)

from swarmdeck.console.sandbox.falsify import cross_entropy, uniform_search  # noqa: E402
from swarmdeck.core.constants import ROBOT_DIAMETER  # noqa: E402

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "near_miss.py"


def closed_form(candidates: NDArray[np.float64]) -> NDArray[np.float64]:
    """The fixture's minimum clearance (m, 0 at a contact) for candidates ``(P, 12)``: straight constant-speed paths."""
    p = len(candidates)
    setup = np.empty((p, 2, 3))
    for k, z in enumerate(candidates):
        setup[k] = np.array(NEAR_MISS_SPACE.decode(z).setup)
    poses = NEAR_MISS_START[None] + setup  # (P, 2, 3)
    vel = NEAR_MISS_SPEED * np.stack((np.cos(poses[..., 2]), np.sin(poses[..., 2])), axis=-1)  # (P, 2, 2)
    r0 = poses[:, 1, :2] - poses[:, 0, :2]
    vr = vel[:, 1] - vel[:, 0]
    t = np.clip(-np.einsum("pd,pd->p", r0, vr) / np.einsum("pd,pd->p", vr, vr), 0.0, NEAR_MISS_DURATION)
    gap = np.linalg.norm(r0 + vr * t[:, None], axis=1)
    return np.maximum(gap - ROBOT_DIAMETER, 0.0)


def jailed_first_contact(seed: int, budget: int) -> int | None:
    from swarmdeck.console.sandbox.executors import SerialExecutor
    from swarmdeck.console.sandbox.falsification import falsify_script
    from swarmdeck.console.sandbox.verification import VerificationConfig, load_script

    ex = SerialExecutor()
    cfg = VerificationConfig(n_robots=2, duration=NEAR_MISS_DURATION, runs=1, seed=seed, paced_runs=0,
                             falsify_budget=budget)
    entry = falsify_script(load_script(EXAMPLE), cfg, 2, lambda tasks: ex.run(tasks, lambda *a: None, lambda: False))
    return entry["worst_case"]["run"] + 1 if entry["found_contact"] else None


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--budget", type=int, default=300, help="the falsifier's budget per seed")
    ap.add_argument("--uniform-cap", type=int, default=20000, help="uniform runs per seed at most")
    ap.add_argument("--check", type=int, default=40, help="candidates on which the closed form is checked")
    ap.add_argument("--jailed", type=int, default=3, help="seeds also searched with jailed runs")
    args = ap.parse_args()
    print(harness.machine())

    rng = np.random.default_rng(0)
    check = np.vstack((rng.uniform(-1, 1, (args.check, 12)), np.sign(rng.uniform(-1, 1, (args.check, 12)))))
    plant, model = near_miss_objective(check), closed_form(check)
    print(f"closed form vs the plant on {len(check)} candidates: largest difference "
          f"{1000 * np.abs(plant - model).max():.2f} mm; contacts agree: {bool(np.all((plant == 0) == (model == 0)))}")
    big = closed_form(np.random.default_rng(1).uniform(-1, 1, (200_000, 12)))
    p = float(np.mean(big == 0.0))
    print(f"P(contact) of a uniform candidate: {p:.2e} (200 000 candidates; 1/p = {1 / p:.0f} runs)")

    ce, un, wall = [], [], []
    for seed in range(args.seeds):
        t0 = time.perf_counter()
        found = cross_entropy(near_miss_objective, NEAR_MISS_SPACE.dim, args.budget, seed).first_at_most(0.0)
        wall.append(time.perf_counter() - t0)
        ce.append(found if found is not None else float("inf"))
        first = uniform_search(closed_form, NEAR_MISS_SPACE.dim, args.uniform_cap, seed, population=1000)
        hit = first.first_at_most(0.0)
        un.append(hit if hit is not None else float("inf"))
        print(f"seed {seed}: cross-entropy {ce[-1]} runs, uniform {un[-1]} runs", flush=True)
    print()
    print(harness.table_header(["search", "runs to the first contact: median", "worst", "seeds", "found"]))
    for name, runs in (("cross-entropy (falsifier)", ce), ("uniform, same search space", un)):
        finite = [r for r in runs if r != float("inf")]
        print(harness.table_row(name, statistics.median(runs), max(runs), len(runs), len(finite)))
    print(f"\nratio of medians: {statistics.median(un) / statistics.median(ce):.0f}x; worst/worst: "
          f"{max(un) / max(ce):.0f}x; in-process falsifier wall per seed: median {statistics.median(wall):.2f} s")
    if args.jailed:
        print()
        print(harness.table_header(["seed", "jailed falsifier: runs to the first contact", "in-process"]))
        for seed in range(args.jailed):
            print(harness.table_row(seed, jailed_first_contact(seed, args.budget), ce[seed]), flush=True)
    assert near_miss_run(np.zeros(12)) > 0.07


if __name__ == "__main__":
    main()
