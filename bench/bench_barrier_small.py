"""The barrier filter's CPU per call at rps sizes (N <= 12), this tree against a baseline revision, interleaved.

An rps 2.x example (tests/data/rps2_examples/master) runs once under ``swarmdeck run`` (in this process, from a
copy of its folder, ``np.random.seed(1)``, 10 s = 303 steps); every call of ``SafetyFilter.solve`` it makes — the
script's own rps barrier and the arena's certify, two a step — is recorded with its filter's configuration. The
recorded calls are then replayed, in order and with one fresh filter per recorded filter (so the warm starts
evolve as in the run), on this tree's ``swarmdeck.safety`` and on the ``safety/`` folder of ``--baseline`` (a git
revision, default the commit before issue 28's small-N work; extracted with ``git archive`` into a temporary
folder and imported as a separate package beside this tree's ``swarmdeck.core``), the two interleaved within
each of ``--repeats`` rounds. Each call is timed with ``time.process_time`` (CPU, robust to a shared machine).
The answers and every diagnostic but the solve time are compared bit for bit.

One command (markdown rows; the load average is printed beside them)::

    python bench/bench_barrier_small.py                       # leader_follower and formation_control
    python bench/bench_barrier_small.py --examples leader_follower/leader_follower.py --repeats 9

Results: bench/RESULTS.md, "barrier at rps sizes".
"""
from __future__ import annotations

import argparse
import dataclasses
import importlib.util
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from types import ModuleType
from typing import Any

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
EXAMPLES = ROOT / "tests" / "data" / "rps2_examples" / "master"
DEFAULT_EXAMPLES = ("leader_follower/leader_follower.py", "formation_control/formation_control.py")
BASELINE = "55d649e"  # main before the small-N barrier work of issue 28 (branch w7-qp7)

Call = tuple[int, Any, Any, Any, Any, Any, Any, Any]


def record(example: str, duration: float) -> list[Call]:
    """The ``SafetyFilter.solve`` calls of one run of ``example``: (filter number, config, P, U, O, extra rows,
    max_speed, robot_bounds), copies."""
    import numpy as np

    from swarmdeck.devices.runner import run_experiment
    from swarmdeck.safety import filter as sf

    calls: list[tuple] = []
    original = sf.SafetyFilter.solve

    def solve(self, P, U, O, extra, max_speed, t0, *, robot_bounds=None):  # type: ignore[no-untyped-def]
        calls.append((id(self), self.config, P.copy(), U.copy(), None if O is None else O.copy(), extra, max_speed,
                      None if robot_bounds is None else robot_bounds.copy()))
        return original(self, P, U, O, extra, max_speed, t0, robot_bounds=robot_bounds)

    with tempfile.TemporaryDirectory(prefix="bench_barrier_small_") as tmp:
        folder = Path(tmp) / "example"
        shutil.copytree((EXAMPLES / example).parent, folder)
        cwd = Path.cwd()
        os.chdir(folder)
        sf.SafetyFilter.solve = solve  # type: ignore[method-assign]
        try:
            np.random.seed(1)
            result = run_experiment(folder / Path(example).name, duration=duration, seed=1, rps=True)
        finally:
            sf.SafetyFilter.solve = original  # type: ignore[method-assign]
            os.chdir(cwd)
    if not result.ok:
        raise SystemExit(f"{example}: the run failed: {result.error}")
    ids: dict[int, int] = {}
    return [(ids.setdefault(c[0], len(ids)), *c[1:]) for c in calls]


def baseline(revision: str, folder: Path) -> ModuleType:
    """``safety/`` of git ``revision`` as the package ``_bench_baseline_safety`` (its ``swarmdeck.core`` imports
    resolve to this tree's)."""
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", revision, "safety"], check=True,
                             capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(folder)], input=archive, check=True)
    name = "_bench_baseline_safety"
    spec = importlib.util.spec_from_file_location(name, folder / "safety" / "__init__.py",
                                                  submodule_search_locations=[str(folder / "safety")])
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    importlib.import_module(f"{name}.filter")
    return module


def replay(calls: list[Call], package: str) -> tuple[list, float]:
    """Every call on ``package``'s filter (``<package>.filter.SafetyFilter``): (answers, CPU seconds in solve)."""
    import numpy as np

    filt = importlib.import_module(f"{package}.filter")
    rows = importlib.import_module(f"{package}.constraints")
    made: dict[int, Any] = {}
    out = []
    cpu = 0.0
    for number, config, P, U, O, extra, max_speed, bounds in calls:
        f = made.get(number)
        if f is None:
            f = made[number] = filt.SafetyFilter(config, robots=P.shape[0])
        ex = None if extra is None else rows.Rows(*(getattr(extra, name) for name in rows._FIELDS))
        start = time.process_time()
        u, diag = f.solve(P, U, O, ex, max_speed, time.perf_counter(), robot_bounds=bounds)
        cpu += time.process_time() - start
        out.append((u, diag))
    assert all(isinstance(u, np.ndarray) for u, _ in out)
    return out, cpu


def same_bits(a: list, b: list) -> bool:
    """The answers and every diagnostic field but ``solve_time_s`` equal to the bit (NaN equal to NaN)."""
    import numpy as np

    def eq(x: Any, y: Any) -> bool:
        if isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
            return (isinstance(x, np.ndarray) and isinstance(y, np.ndarray) and x.dtype == y.dtype
                    and x.shape == y.shape and x.tobytes() == y.tobytes())
        return bool(x == y or (x != x and y != y))

    for (ua, da), (ub, db) in zip(a, b, strict=True):
        if not eq(ua, ub):
            return False
        for field in dataclasses.fields(da):
            if field.name != "solve_time_s" and not eq(getattr(da, field.name), getattr(db, field.name)):
                return False
    return True


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--examples", nargs="+", default=list(DEFAULT_EXAMPLES),
                        help="rps 2.x examples, relative to tests/data/rps2_examples/master")
    parser.add_argument("--baseline", default=BASELINE, help="git revision to compare with ('' for none)")
    parser.add_argument("--repeats", type=int, default=5, help="interleaved rounds (median and worst reported)")
    parser.add_argument("--duration", type=float, default=10.0, help="experiment time per run, s")
    args = parser.parse_args()
    os.environ.setdefault("MPLBACKEND", "Agg")
    print(harness.machine())
    with tempfile.TemporaryDirectory(prefix="bench_barrier_small_base_") as tmp:
        packages = [("this tree", "swarmdeck.safety")]
        if args.baseline:
            baseline(args.baseline, Path(tmp))
            packages.insert(0, (f"baseline {args.baseline}", "_bench_baseline_safety"))
        print("| example | calls | " + " | ".join(f"{name} ms/call median / worst" for name, _ in packages)
              + (" | baseline / this tree (medians) | same bits" if len(packages) == 2 else "") + " | load |")
        print("| --- | ---: | " + " | ".join("---:" for _ in packages) + (" | ---: | ---" if len(packages) == 2 else "")
              + " | ---: |")
        for example in args.examples:
            calls = record(example, args.duration)
            per: dict[str, list[float]] = {name: [] for name, _ in packages}
            answers: dict[str, list] = {}
            for _ in range(args.repeats):
                for name, package in packages:
                    out, cpu = replay(calls, package)
                    per[name].append(cpu / len(calls) * 1e3)
                    answers.setdefault(name, out)
            cells = [f"{statistics.median(per[name]):.3f} / {max(per[name]):.3f}" for name, _ in packages]
            row = f"| {example} | {len(calls)} | " + " | ".join(cells)
            if len(packages) == 2:
                (a, _), (b, _) = packages
                ratio = statistics.median(per[a]) / statistics.median(per[b])
                row += f" | {ratio:.2f}x | {'yes' if same_bits(answers[a], answers[b]) else 'NO'}"
            print(row + f" | {os.getloadavg()[0]:.1f} |")


if __name__ == "__main__":
    main()
