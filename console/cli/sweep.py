"""``swarmdeck sweep SCRIPT --param NAME=VALUES ... --seeds K -o DIR``: a parameter sweep in sandboxed simulation.

Exit status: 0 every run finished (failed runs included: they are rows of the table), 1 the sweep stopped before
every run finished (what finished is kept: the same command continues it), 2 usage or infrastructure error.
"""
from __future__ import annotations

import argparse
import sys

NAME = "sweep"
HELP = "sweep a script's parameters over seeds and robot counts in sandboxed simulation: table, CIs, plots, report"
ORDER = 26


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.epilog = (
        "the script declares its parameters with defaults: `from swarmdeck.devices import params, record_metrics; "
        "p = params(gain=1.0, spacing=0.3)` (run alone it gets the defaults) and may report metrics with "
        "`record_metrics(error=...)`. VALUES: 0.5:2:4 (4 values from 0.5 to 2), log:0.1:10:5 (5 log-spaced), "
        "0.5,1,2 (these). Outputs in DIR: results.csv, results.parquet (with pyarrow), summary.csv, plots/*.png, "
        "report.html; runs/ caches finished runs, so an interrupted sweep continues when run again. "
        "exit status: 0 all runs finished, 1 stopped early (resumable), 2 usage or infrastructure error.")
    parser.add_argument("script", metavar="SCRIPT",
                        help="the experiment script (.py, or a directory run from its --entry file)")
    parser.add_argument("--entry", default=None, metavar="FILE", help="for a directory SCRIPT: the file to run")
    parser.add_argument("--param", action="append", default=[], metavar="NAME=VALUES",
                        help="a swept parameter the script declares (repeat for each): NAME=0.5:2:4, "
                             "NAME=log:0.1:10:5 or NAME=0.5,1,2")
    parser.add_argument("--seeds", type=int, default=1, metavar="K", help="runs per point, seeds 0..K-1 (default 1)")
    parser.add_argument("--seed", type=int, default=0, metavar="S",
                        help="first seed (runs use S..S+K-1) and the random design's seed (default 0)")
    parser.add_argument("--robots", default=None, metavar="N[,N...]",
                        help="robot counts to sweep, e.g. 10,20 or 10:50:5 (default: the script's own); a script "
                             "declaring a `robots` parameter gets the count as its value too")
    parser.add_argument("--design", choices=("grid", "random"), default="grid",
                        help="grid: every combination (default); random: --samples points drawn in the ranges")
    parser.add_argument("--samples", type=int, default=None, metavar="M", help="points of a random design")
    parser.add_argument("--duration", type=float, default=30.0, metavar="S", help="simulated seconds per run (default 30)")
    parser.add_argument("--no-barrier", action="store_true",
                        help="run without the safety barrier (raw runs: what the controller does alone)")
    parser.add_argument("--capsules", action="store_true",
                        help="record every run and write its capsule to DIR/capsules/KEY.zip (KEY: the run's row in "
                             "DIR/runs): `swarmdeck run DIR/capsules/KEY.zip` reproduces that run bit for bit")
    parser.add_argument("--workers", type=int, default=None, metavar="W",
                        help="local worker processes (default: number of cores)")
    parser.add_argument("--ray", default=None, metavar="auto|ADDRESS|local",
                        help="run on a Ray cluster ('auto': the running one; 'local': start one here); needs "
                             "swarmdeck[ray] and swarmdeck on every node")
    parser.add_argument("--trusted", action="store_true",
                        help="run the script unconfined where this machine cannot confine it (no jail works)")
    parser.add_argument("--allow-no-cgroup", action="store_true",
                        help="run even where no cgroup can be created per run (only per-process limits)")
    parser.add_argument("--rps", action=argparse.BooleanOptionalAction, default=None,
                        help="resolve `import rps...` to swarmdeck's rps facade (default: when no real rps is installed)")
    parser.add_argument("-o", "--output", required=True, metavar="DIR", help="the sweep's folder (created; reused to resume)")


def _progress(total: int, already: int):
    if not sys.stderr.isatty():
        return None, lambda: None
    from tqdm import tqdm

    bar = tqdm(total=total, initial=already, unit="run", desc="sweeping", file=sys.stderr)
    return (lambda p: bar.update(1)), bar.close


def spec_from(args: argparse.Namespace):
    """The :class:`~swarmdeck.console.sweep.campaign.SweepSpec` of the command line; UsageError naming what is wrong."""
    from swarmdeck.console.cli import UsageError
    from swarmdeck.console.cli.run import check_run_arguments
    from swarmdeck.console.sandbox.confinement import JailConfig
    from swarmdeck.console.sandbox.verification import VerificationConfig, load_script
    from swarmdeck.console.sweep.campaign import SweepSpec
    from swarmdeck.console.sweep.design import DesignError, parse_axis, parse_counts

    check_run_arguments(None, args.duration, seed=args.seed)
    try:
        axes = [parse_axis(p) for p in args.param]
        robots_text = args.robots
        given = [a for a in axes if a.name == "robots"]
        if given:  # --param robots=... is --robots
            if robots_text is not None:
                raise DesignError("give the robot counts once: --robots or --param robots=..., not both")
            robots_text = args.param[axes.index(given[0])].partition("=")[2]
            axes = [a for a in axes if a.name != "robots"]
        robots = parse_counts(robots_text, "robots")
        bundle = load_script(args.script, args.entry)
        config = VerificationConfig(duration=args.duration, trusted=args.trusted, rps=args.rps,
                                    jail=JailConfig(allow_no_cgroup=args.allow_no_cgroup))
        return SweepSpec(bundle, tuple(axes), seeds=args.seeds, first_seed=args.seed, robots=robots,
                         design=args.design, samples=args.samples, design_seed=args.seed, config=config,
                         barrier=not args.no_barrier, capsules=args.capsules)
    except ValueError as exc:
        raise UsageError(str(exc)) from None


def main(args: argparse.Namespace) -> int:
    from swarmdeck.console.cli import UsageError
    from swarmdeck.console.sandbox.confinement import ConfinementUnavailable
    from swarmdeck.console.sandbox.executors import LocalPoolExecutor, RayExecutor
    from swarmdeck.console.sweep.campaign import RunCache, SweepIncomplete, plan, run_sweep
    from swarmdeck.console.sweep.design import DesignError

    spec = spec_from(args)
    if args.workers is not None and args.workers < 1:
        raise UsageError(f"--workers must be >= 1, got {args.workers}")
    if args.workers is not None and args.ray:
        raise UsageError("--workers is for the local pool; with --ray the cluster decides (give one of them)")
    try:
        the_plan = plan(spec)  # refused before any run or any executor starts
        executor = RayExecutor(args.ray) if args.ray else LocalPoolExecutor(args.workers)
    except (ValueError, RuntimeError) as exc:
        raise UsageError(str(exc)) from None
    from pathlib import Path

    cache = RunCache(Path(args.output) / "runs")
    already = sum(1 for r in the_plan.runs if cache.get(r.key) is not None)
    on_progress, close = _progress(len(the_plan.runs), already)
    try:
        result = run_sweep(spec, args.output, executor, on_progress=on_progress)
    except SweepIncomplete as exc:
        close()
        print(f"swarmdeck sweep: {exc}", file=sys.stderr)
        return 1
    except (DesignError, ConfinementUnavailable) as exc:
        raise UsageError(str(exc)) from None
    finally:
        close()
    print(f"{len(result.rows)} runs ({result.ran} run now, {result.cached} from earlier), {result.failed} failed "
          f"[{result.executor}]")
    print(f"table: {Path(args.output) / 'results.csv'}; report: {Path(args.output) / 'report.html'}")
    if args.capsules:
        print(f"capsules: {Path(args.output) / 'capsules'}/KEY.zip (`swarmdeck run KEY.zip` reproduces a run)")
    return 0
