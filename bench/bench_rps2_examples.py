"""The Robotarium 2.0 examples (tests/data/rps2_examples/master) under swarmdeck vs under rps 2.0 itself.

Each example runs unchanged, in a fresh process, from a copy of its folder, with ``np.random.seed(1)``, for the same
simulated experiment time (``--duration``, default 10 s = 303 steps of 0.033 s; shorter examples end by themselves),
on matplotlib's Agg backend (no window), in these modes, interleaved:

* ``rps`` — the Robotarium's own simulator (``robotarium_python_simulator`` at b23069e, cvxopt) as the script asks:
  its figure drawn every step, ``sim_in_real_time`` as the script sets it (each step waits for 0.033 s of wall time),
  and its initialisation phase (the robots drive from the chargers to the initial conditions first);
* ``rps unpaced`` — the same with ``sim_in_real_time=False`` (forced; what a user can do to get results fast);
* ``rps headless`` — unpaced and ``show_figure=False`` (forced; only for examples that never touch the figure);
* ``swarmdeck`` — ``swarmdeck run SCRIPT --duration D``: the arena's barrier on every step, headless;
* ``swarmdeck rps`` — ``swarmdeck run --rps-semantics`` (the script's own barrier only);
* ``floor`` — what both sides pay before any simulator runs: a process that starts Python and imports numpy, and
  matplotlib's pyplot on Agg for the examples that plot (the script imports it, or draws on ``r.axes``, which needs
  it under either simulator). The last two columns compare what each simulator adds above it: (rps unpaced − floor)
  / (swarmdeck − floor), medians. rps 2.0 imports pyplot in every example (``robotarium_abc``); that is counted as
  rps's own cost where the script does not plot.

The rps runs stop at the same experiment time by counting ``step()`` calls after rps's initialisation (the script is
not edited; the count is a wrapper around rps's ``step``).

Measured per run: *CPU* — user + system seconds of the whole child process (``resource.getrusage(RUSAGE_CHILDREN)``
before and after it, so the interpreter's start, every import — rps's matplotlib and cvxopt, swarmdeck's scipy and
numba and its cached kernels — and the run itself; robust to the load of a shared machine), and *wall* — seconds of the
script's run in the child (from just before the script starts, imports of swarmdeck's runner excluded). Each cell is
the median over ``--repeats`` runs (default 3) and the worst (slowest) of them, the modes interleaved within each
repeat, their order turned by one from repeat to repeat (so no mode always runs right after another; with
``--repeats`` a multiple of the number of modes, every mode runs once in every position). The ratio columns
are rps unpaced / swarmdeck on CPU: of the medians, and the worst case (rps's fastest run against swarmdeck's
slowest). swarmdeck's numba kernels are compiled once per installation into ``__pycache__``
(``cache=True``); a first warm-up run per example (not counted) makes every counted run load them, as every run after
the first does for a user (``--no-warm-up`` counts the first too). Compiled Python modules (``__pycache__``) are kept
the same way for both sides: the children run without ``PYTHONDONTWRITEBYTECODE`` (a sandbox's shell may set it; a
user's Python does not), swarmdeck's are written by the warm-up run and rps's (the ``--rps-path`` folders) are
byte-compiled before the first run, so neither side pays for compiling its own source on every run.

Get rps 2.0 and cvxopt beside it (any folders)::

    git -C <clone of robotarium/robotarium_python_simulator> archive b23069e | tar -x -C /tmp/rps2_src
    pip install --target /tmp/rps2_deps cvxopt
    python bench/bench_rps2_examples.py --rps-path /tmp/rps2_src --rps-path /tmp/rps2_deps

Results: bench/RESULTS.md, "Robotarium 2.x examples".
"""
from __future__ import annotations

import argparse
import compileall
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads

HERE = Path(__file__).resolve().parent
EXAMPLES = HERE.parent / "tests" / "data" / "rps2_examples" / "master"
#: (example, touches the figure)
CASES = [
    ("go_to_goal/go_to_point_si.py", False),
    ("go_to_goal/go_to_pose_hybrid.py", False),
    ("barrier_certificates/si_barriers.py", False),
    ("barrier_certificates/uni_barriers.py", False),
    ("consensus/consensus_fewer_errors.py", False),
    ("formation_control/formation_control.py", False),
    ("leader_follower/leader_follower.py", False),
    ("plotting/barriers_with_plotting.py", True),
    ("plotting/leader_follower_with_plotting.py", True),
    ("sensors/sensor_readings.py", False),
    ("state_estimation/dead_reckoning/dead_reckoning.py", True),
]
MODES = ("rps", "rps unpaced", "rps headless", "swarmdeck", "swarmdeck rps", "floor")


class _Enough(Exception):
    """The experiment time is over (rps side)."""


def _child_rps(mode: str, script: Path, duration: float) -> dict:
    import matplotlib

    matplotlib.use("Agg")
    import runpy

    import numpy as np
    import rps.robotarium as rr

    steps = int(round(duration / rr.Robotarium.TIME_STEP))
    counted = {"n": 0}
    init, step = rr.Robotarium.__init__, rr.Robotarium.step

    def patched_init(self, **kwargs):
        if mode != "rps":
            kwargs["sim_in_real_time"] = False
        if mode == "rps headless":
            kwargs["show_figure"] = False
        init(self, **kwargs)

    def patched_step(self):
        step(self)
        if not self.initializing:
            counted["n"] += 1
            if counted["n"] >= steps:
                raise _Enough

    rr.Robotarium.__init__, rr.Robotarium.step = patched_init, patched_step
    np.random.seed(1)
    sys.argv = [str(script)]
    start = time.perf_counter()
    try:
        runpy.run_path(str(script), run_name="__main__")
    except _Enough:
        pass
    return {"seconds": time.perf_counter() - start, "steps": counted["n"]}


def _child_floor(mode: str, script: Path, duration: float) -> dict:
    """The imports both sides pay (see ``floor`` in the module docstring)."""
    import numpy  # noqa: F401

    if next(fig for name, fig in CASES if Path(name).name == script.name):
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot  # noqa: F401
    return {"seconds": 0.0, "steps": 0}


def _child_swarmdeck(mode: str, script: Path, duration: float) -> dict:
    import numpy as np

    from swarmdeck.devices.runner import run_experiment

    np.random.seed(1)
    start = time.perf_counter()
    result = run_experiment(script, duration=duration, seed=1, rps=True, rps_semantics=mode == "swarmdeck rps")
    seconds = time.perf_counter() - start
    if not result.ok:
        raise SystemExit(result.error)
    report = result.reports[0]
    return {"seconds": seconds, "steps": report.validation.steps, "collisions": report.validation.steps_with_collision}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rps-path", action="append", default=[], metavar="DIR",
                        help="a folder with rps 2.0 (and one with cvxopt); without: swarmdeck only")
    parser.add_argument("--duration", type=float, default=10.0, help="simulated experiment seconds per run")
    parser.add_argument("--repeats", type=int, default=3, help="runs per example and mode; cells are medians")
    parser.add_argument("--no-warm-up", action="store_true",
                        help="count the first swarmdeck run too (by default one uncounted run loads or compiles numba's "
                             "kernel cache first)")
    parser.add_argument("--only", default=None, help="run the examples whose path contains this")
    parser.add_argument("--modes", default=",".join(MODES), help=f"comma-separated, of {', '.join(MODES)}")
    parser.add_argument("--child", nargs=3, metavar=("MODE", "SCRIPT", "DURATION"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        mode, script, duration = args.child[0], Path(args.child[1]), float(args.child[2])
        run = _child_rps if mode.startswith("rps") else _child_floor if mode == "floor" else _child_swarmdeck
        out = run(mode, script, duration)
        print("RESULT " + json.dumps(out))
        return
    if args.repeats < 1:
        raise SystemExit(f"--repeats must be at least 1, got {args.repeats}")
    print(harness.machine())
    for folder in args.rps_path:  # rps's modules compiled once, as swarmdeck's are by the warm-up run
        compileall.compile_dir(folder, quiet=1)
    cases = [(n, fig) for n, fig in CASES if args.only is None or args.only in n]
    chosen = [m.strip() for m in args.modes.split(",")]
    unknown = sorted(set(chosen) - set(MODES))
    if unknown:
        raise SystemExit(f"--modes: unknown mode(s) {unknown}; choose from {', '.join(MODES)}")
    modes = [m for m in MODES if m in chosen and (args.rps_path or not m.startswith("rps"))]
    print(harness.table_header(["example", *[f"{m} CPU median / worst (wall) s" for m in modes],
                                "rps unpaced / swarmdeck (CPU, medians)",
                                "worst case (rps's fastest / swarmdeck's slowest)",
                                "above the floor: rps unpaced / swarmdeck (medians; worst case)"]))
    for name, uses_figure in cases:
        cpu: dict[str, list[float]] = {}
        wall: dict[str, list[float]] = {}
        if not args.no_warm_up:
            for mode in modes:
                if mode.startswith("swarmdeck"):
                    _run_child(args, name, mode)
        for k in range(args.repeats):
            # interleaved: a change of the machine's load hits every mode alike; the order turns by one each repeat,
            # so no mode always runs right after another
            for mode in modes[k % len(modes):] + modes[:k % len(modes)]:
                if mode == "rps headless" and uses_figure:
                    continue
                seconds, result = _run_child(args, name, mode)
                cpu.setdefault(mode, []).append(seconds)
                wall.setdefault(mode, []).append(result["seconds"])
        med = {m: statistics.median(v) for m, v in cpu.items()}
        cells = [f"{med[m]:.2f} / {max(cpu[m]):.2f} ({statistics.median(wall[m]):.2f})" if m in med else "—"
                 for m in modes]
        both = {"rps unpaced", "swarmdeck"} <= set(med)
        ratio = f"{med['rps unpaced'] / med['swarmdeck']:.1f}×" if both else "—"
        worst = f"{min(cpu['rps unpaced']) / max(cpu['swarmdeck']):.1f}×" if both else "—"
        above = "—"
        if both and "floor" in med:
            f = med["floor"]
            above = (f"{(med['rps unpaced'] - f) / (med['swarmdeck'] - f):.1f}× "
                     f"({(min(cpu['rps unpaced']) - f) / (max(cpu['swarmdeck']) - f):.1f}×)")
        print(harness.table_row(name, *cells, ratio, worst, above), flush=True)


def _run_child(args: argparse.Namespace, name: str, mode: str) -> tuple[float, dict]:
    """One run of example ``name`` under ``mode`` in a fresh process: (its CPU seconds, user + system, the child's
    RESULT dict); a SystemExit naming the example, the mode and the child's output when it failed."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / Path(name).parent
        shutil.copytree((EXAMPLES / name).parent, folder)
        env = dict(os.environ, MPLBACKEND="Agg")
        env.pop("PYTHONDONTWRITEBYTECODE", None)  # a user's Python keeps compiled modules (see the docstring)
        if mode.startswith("rps"):
            env["PYTHONPATH"] = os.pathsep.join([*args.rps_path, env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        done = subprocess.run([*harness.python(), __file__, "--child", mode, str(folder / Path(name).name),
                               str(args.duration)], env=env, capture_output=True, text=True, cwd=folder, check=False)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise SystemExit(f"{name} under {mode} failed:\n{done.stdout[-2000:]}\n{done.stderr[-4000:]}")
    seconds = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return seconds, json.loads(next(x for x in done.stdout.splitlines() if x.startswith("RESULT "))[7:])


if __name__ == "__main__":
    main()
