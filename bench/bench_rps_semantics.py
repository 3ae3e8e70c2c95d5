"""MARBLER on the real rps vs swarmdeck's rps facade (`--rps-semantics`, and the default with the barrier).

MARBLER's own code (tests/data/marbler, its learning part shimmed as in the tests) runs its Warehouse
scenario in its training configuration (README: ``robotarium: False``, ``real_time: False``, no figures;
here also no GIFs and no TensorBoard logging), in a fresh process per run, on:

* ``rps``: the Robotarium's own simulator at the commit MARBLER names (6bb184e, rps 1.x) with its
  dependency cvxopt — pass ``--rps-path DIR`` where ``DIR`` holds both, e.g.::

      git -C <robotarium_python_simulator clone> archive 6bb184e | tar -x -C /tmp/rps_src
      pip install --target /tmp/rps_deps cvxopt
      python bench/bench_rps_semantics.py --rps-path /tmp/rps_src --rps-path /tmp/rps_deps

  (matplotlib ≥ 3.9 removed ``cm.get_cmap``, which MARBLER calls: it is put back for this run, as the
  facade does);
* ``facade --rps-semantics`` and ``facade`` (default: swarmdeck's barrier on every step).

Prints env steps/s (MARBLER's steps, each 29 simulator steps) and simulator steps/s, then the cost of one
simulator step alone at N = 6, 20, 50 (with ``--rps-path``); PredatorCapturePrey
cannot run on numpy 2 (``ndarray == []`` raises), on either simulator. Results: bench/RESULTS.md, "rps semantics".
"""
from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

from marbler_fixtures import marbler_copy, marbler_env  # noqa: E402

TRAINING = {"show_figure_frequency": "-1", "save_gif": "False", "enable_logging": "False"}


def _child(mode: str, main: str, scenario: str) -> None:
    """One run in this process; prints a JSON line."""
    argv = ["--scenario", scenario]
    out = io.StringIO()
    if mode == "rps":
        import matplotlib
        import matplotlib.cm

        if not hasattr(matplotlib.cm, "get_cmap"):
            matplotlib.cm.get_cmap = lambda name=None, lut=None: (  # what the facade provides too
                matplotlib.colormaps[name] if lut is None else matplotlib.colormaps[name].resampled(lut))
        import runpy

        sys.path.insert(0, str(Path(main).parent))
        sys.argv = [main, *argv]
        start = time.perf_counter()
        with contextlib.redirect_stdout(out):
            runpy.run_path(main, run_name="__main__")
        elapsed = time.perf_counter() - start
    else:
        from swarmdeck.devices.runner import run_experiment

        start = time.perf_counter()
        with contextlib.redirect_stdout(out):
            result = run_experiment(main, argv=argv, rps=True, rps_semantics=mode == "facade-rps")
        elapsed = time.perf_counter() - start
        if not result.ok:
            raise SystemExit(result.error)
    text = out.getvalue()
    steps = [int(s) for s in re.findall(r"^Episode steps: (\d+)", text, re.MULTILINE)]
    if not steps:
        raise SystemExit(f"no episode finished:\n{text[-2000:]}")
    print(json.dumps({"mode": mode, "episodes": len(steps), "env_steps": sum(steps), "seconds": elapsed}))


def _steps(n: int, k: int = 500) -> dict[str, float]:
    """µs per get_poses/set_velocities/step of the real rps (already on sys.path) and the facade in rps
    semantics, interleaved, best of 5."""
    import matplotlib
    import numpy as np

    matplotlib.use("Agg")
    import rps.robotarium as real

    from swarmdeck.devices.rps.robotarium import Robotarium

    ic = np.array([np.linspace(-1.4, 1.4, n), np.zeros(n), np.zeros(n)])
    vel = np.vstack((np.zeros(n), np.full(n, 0.3)))
    best: dict[str, float] = {}
    for _ in range(5):
        for mode in ("rps", "facade-rps"):
            r = (real.Robotarium(number_of_robots=n, show_figure=False, initial_conditions=ic.copy(), sim_in_real_time=False)
                 if mode == "rps" else Robotarium(n, show_figure=False, initial_conditions=ic.copy(), sim_in_real_time=False,
                                                  rps_semantics=True))
            for _ in range(20):
                r.get_poses()
                r.set_velocities(np.arange(n), vel)
                r.step()
            start = time.perf_counter()
            for _ in range(k):
                r.get_poses()
                r.set_velocities(np.arange(n), vel)
                r.step()
            best[mode] = min(best.get(mode, 1e9), (time.perf_counter() - start) / k * 1e6)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rps-path", action="append", default=[], metavar="DIR",
                        help="a folder with the real rps (and one with cvxopt); without: the facade only")
    parser.add_argument("--episodes", type=int, default=5)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--scenario", default="Warehouse")
    parser.add_argument("--child", nargs=3, metavar=("MODE", "MAIN", "SCENARIO"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        if args.child[0] == "steps":
            print(json.dumps(_steps(int(args.child[1]))))
        else:
            _child(*args.child)
        return
    with tempfile.TemporaryDirectory() as tmp:
        main_py = marbler_copy(Path(tmp), episodes=args.episodes)
        config = main_py.parent / "scenarios" / args.scenario / "config.yaml"
        text = config.read_text()
        for key, value in TRAINING.items():
            text = re.sub(rf"^{key}:.*$", f"{key}: {value}", text, flags=re.MULTILINE)
        config.write_text(text)
        modes = (["rps"] if args.rps_path else []) + ["facade-rps", "facade"]
        rows: dict[str, list[dict]] = {m: [] for m in modes}
        for _ in range(args.repeats):
            for mode in modes:  # interleaved: a change in the machine's load hits every mode alike
                env = marbler_env(main_py)
                env["MPLBACKEND"] = "Agg"
                if mode == "rps":
                    env["PYTHONPATH"] = os.pathsep.join([*args.rps_path, env["PYTHONPATH"]])
                done = subprocess.run([*harness.python(), __file__, "--child", mode, str(main_py), args.scenario],
                                      env=env, capture_output=True, text=True, cwd=tmp, check=False)
                if done.returncode != 0:
                    raise SystemExit(f"{mode} failed:\n{done.stdout[-2000:]}\n{done.stderr[-4000:]}")
                line = next(x for x in done.stdout.splitlines() if x.startswith('{"mode"'))  # (MARBLER prints at exit)
                rows[mode].append(json.loads(line))
    print(f"MARBLER {args.scenario}, {args.episodes} episodes per run, best of {args.repeats} (env step = 29 sim steps)")
    print(f"{'simulator':<28} {'env steps/s':>12} {'sim steps/s':>12} {'mean episode length':>20}")
    names = {"rps": "rps 1.x (6bb184e, cvxopt)", "facade-rps": "facade --rps-semantics", "facade": "facade (barrier every step)"}
    for mode, runs in rows.items():
        best = max(runs, key=lambda r: r["env_steps"] / r["seconds"])
        rate = best["env_steps"] / best["seconds"]
        mean_len = sum(r["env_steps"] for r in runs) / sum(r["episodes"] for r in runs)
        print(f"{names[mode]:<28} {rate:>12.1f} {29 * rate:>12.0f} {mean_len:>20.1f}")
    if args.rps_path:
        print("\nµs per simulator step (get_poses, set_velocities, step), best of 5, interleaved")
        print(f"{'N':>4} {'rps 1.x':>10} {'facade --rps-semantics':>24}")
        for n in (6, 20, 50):
            env = dict(os.environ, PYTHONPATH=os.pathsep.join([*args.rps_path, os.environ.get("PYTHONPATH", "")]))
            done = subprocess.run([*harness.python(), __file__, "--child", "steps", str(n), "-"], env=env,
                                  capture_output=True, text=True, check=True)
            row = json.loads(done.stdout.strip().splitlines()[-1])
            print(f"{n:>4} {row['rps']:>10.0f} {row['facade-rps']:>24.0f}")


if __name__ == "__main__":
    main()
