"""The devices' share of an rps 2.x example's run under ``swarmdeck run`` (issue 28: the run time against rps 2.x):
the figure projection and the arena's step outside the safety filter and the sensors, against a baseline tree.

Each example of ``bench_rps2_examples.py`` (default: the three the figure projection and the step touch most, and
two without a figure) runs unchanged in a fresh process, as ``swarmdeck run`` (the arena's barrier on), for 10 s of
experiment time, with ``np.random.seed(1)``, on matplotlib's Agg backend, in two kinds of child:

* *plain* — nothing added: the whole process's CPU seconds (user + system: interpreter, imports, the run);
* *parts* — CPU time (``time.thread_time``) inside the rps facade's figure projection (``_project_figure``), the
  arena's step (``Arena.step``/``step_unicycle``), the arena's safety filter (``UnicycleSafetyFilter.filter``), the
  script's own barrier (``SafetyFilter.solve`` outside the arena's step) and the sensors
  (``Arena._sense_after_step``); "devices step" is the arena's step without the arena's filter and the sensors,
  plus the facade's ``step``/``get_poses`` around it.

With ``--baseline DIR`` (a folder holding an older swarmdeck as ``DIR/swarmdeck``, e.g.
``mkdir -p /tmp/base/swarmdeck && git archive 55d649e console core coverage devices envs network safety sensing
tracking examples | tar -x -C /tmp/base/swarmdeck``) every repeat runs the baseline and this tree interleaved, so a
change of the machine's load hits both alike. Cells: median / worst over ``--repeats`` (default 3), CPU seconds
(process) or milliseconds (parts); the load average is printed with the machine line.

One command (from the repository root)::

    .venv/bin/python bench/bench_rps2_step_share.py --baseline /tmp/base
"""
from __future__ import annotations

import argparse
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
from typing import Any

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads

HERE = Path(__file__).resolve().parent
EXAMPLES = HERE.parent / "tests" / "data" / "rps2_examples" / "master"
CASES = ("plotting/barriers_with_plotting.py", "plotting/leader_follower_with_plotting.py",
         "state_estimation/dead_reckoning/dead_reckoning.py", "leader_follower/leader_follower.py",
         "formation_control/formation_control.py")
#: (module, qualified name, part) timed in a parts child
TIMED = (("swarmdeck.devices.rps.robotarium", "Robotarium.step", "facade step"),
         ("swarmdeck.devices.rps.robotarium", "Robotarium.get_poses", "get_poses"),
         ("swarmdeck.devices.rps.robotarium", "Robotarium._project_figure", "figure"),
         ("swarmdeck.devices.arena", "Arena.step", "arena step"),
         ("swarmdeck.devices.arena", "Arena.step_unicycle", "arena step"),
         ("swarmdeck.devices.arena", "Arena._sense_after_step", "sensors"),
         ("swarmdeck.safety.unicycle", "UnicycleSafetyFilter.filter", "arena filter"),
         ("swarmdeck.safety.filter", "SafetyFilter.solve", "solve"))


def _child(mode: str, script: Path) -> dict[str, Any]:
    import importlib

    import numpy as np

    totals: dict[str, float] = {}
    depth = {"arena": 0}
    outside = {"solve": 0.0}  # QP solves outside the arena's step: the script's own barrier
    if mode == "parts":
        for module, qualname, part in TIMED:
            owner: Any = importlib.import_module(module)
            *path, name = qualname.split(".")
            for attr in path:
                owner = getattr(owner, attr)
            inner = getattr(owner, name)

            def timed(*a: Any, _inner: Any = inner, _part: str = part, **k: Any) -> Any:
                t = time.thread_time()
                if _part == "arena step":
                    depth["arena"] += 1
                try:
                    return _inner(*a, **k)
                finally:
                    spent = time.thread_time() - t
                    if _part == "arena step":
                        depth["arena"] -= 1
                    if _part == "solve" and not depth["arena"]:
                        outside["solve"] += spent
                    totals[_part] = totals.get(_part, 0.0) + spent

            setattr(owner, name, timed)
    from swarmdeck.devices.runner import run_experiment

    np.random.seed(1)
    result = run_experiment(script, duration=10.0, seed=1, rps=True)
    if not result.ok:
        raise SystemExit(result.error)
    out: dict[str, Any] = {"steps": result.reports[0].validation.steps}
    if mode == "parts":
        facade_extra = totals.get("facade step", 0.0) - totals.get("arena step", 0.0) - totals.get("figure", 0.0)
        out["figure"] = totals.get("figure", 0.0)
        out["devices step"] = (totals.get("arena step", 0.0) - totals.get("arena filter", 0.0)
                               - totals.get("sensors", 0.0) + facade_extra + totals.get("get_poses", 0.0))
        out["arena filter"] = totals.get("arena filter", 0.0)
        out["script filter"] = outside["solve"]
    return out


def _run(name: str, mode: str, tree: str | None) -> tuple[float, dict[str, Any]]:
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / Path(name).parent
        shutil.copytree((EXAMPLES / name).parent, folder)
        env = dict(os.environ, MPLBACKEND="Agg")
        env.pop("PYTHONDONTWRITEBYTECODE", None)  # compiled modules kept, as a user's Python does
        if tree is not None:
            env["PYTHONPATH"] = os.pathsep.join([tree, env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        done = subprocess.run([*harness.python(), __file__, "--child", mode, str(folder / Path(name).name)], env=env,
                              capture_output=True, text=True, cwd=folder, check=False, timeout=600)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise SystemExit(f"{name} ({mode}, tree {tree or 'this'}) failed:\n{done.stdout[-2000:]}\n{done.stderr[-4000:]}")
    seconds = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return seconds, json.loads(next(x for x in done.stdout.splitlines() if x.startswith("RESULT "))[7:])


def _cell(values: list[float], scale: float = 1.0, digits: int = 2) -> str:
    return f"{statistics.median(values) * scale:.{digits}f} / {max(values) * scale:.{digits}f}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--baseline", default=None, metavar="DIR", help="a folder with an older swarmdeck as DIR/swarmdeck")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--only", default=None, help="the examples whose path contains this")
    parser.add_argument("--child", nargs=2, metavar=("MODE", "SCRIPT"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        print("RESULT " + json.dumps(_child(args.child[0], Path(args.child[1]))))
        return
    if args.repeats < 1:
        raise SystemExit(f"--repeats must be at least 1, got {args.repeats}")
    print(harness.machine())
    trees: list[tuple[str, str | None]] = [("this tree", None)]
    if args.baseline is not None:
        if not (Path(args.baseline) / "swarmdeck").is_dir():
            raise SystemExit(f"--baseline {args.baseline}: no swarmdeck folder in it")
        trees.insert(0, ("baseline", str(Path(args.baseline).resolve())))
    print(harness.table_header(["example", "tree", "process CPU s (median / worst)", "figure ms", "devices step ms",
                                "arena filter ms", "script's filter ms", "load"]))
    for name in [c for c in CASES if args.only is None or args.only in c]:
        for _, tree in trees:  # warm-up: compiled modules and numba caches written, not counted
            _run(name, "plain", tree)
        cpu: dict[str, list[float]] = {}
        parts: dict[str, dict[str, list[float]]] = {}
        for _ in range(args.repeats):
            for label, tree in trees:
                cpu.setdefault(label, []).append(_run(name, "plain", tree)[0])
                got = _run(name, "parts", tree)[1]
                for key in ("figure", "devices step", "arena filter", "script filter"):
                    parts.setdefault(label, {}).setdefault(key, []).append(got[key])
        load = f"{os.getloadavg()[0]:.1f}"
        for label, _ in trees:
            p = parts[label]
            print(harness.table_row(name, label, _cell(cpu[label]), _cell(p["figure"], 1e3, 0),
                                    _cell(p["devices step"], 1e3, 0), _cell(p["arena filter"], 1e3, 0),
                                    _cell(p["script filter"], 1e3, 0), load), flush=True)


if __name__ == "__main__":
    sys.exit(main())
