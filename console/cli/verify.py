"""``swarmdeck verify SCRIPT...``: verify untrusted experiment scripts in sandboxed simulation.

Exit status: 0 accepted (with or without barrier bypass), 1 rejected, 2 usage or
infrastructure error (bad option, unreadable script, no confinement without
``--trusted``, Ray unavailable).
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

NAME = "verify"
HELP = "verify experiment scripts in sandboxed simulation: safety score, verdict, JSON/HTML report"
ORDER = 25


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.epilog = ("verdicts: rejected | accepted (runs with the barrier) | accepted, may bypass the barrier. "
                     "exit status: 0 accepted, 1 rejected, 2 usage or infrastructure error.")
    parser.add_argument("scripts", nargs="+", metavar="SCRIPT",
                        help="experiment scripts (experiment(arena) or rps style): .py files, or directories run from "
                             "their --entry file with sibling modules importable")
    parser.add_argument("--entry", default=None, metavar="FILE",
                        help="for a directory SCRIPT: the file to run, relative to it (default main.py)")
    parser.add_argument("--manifest", default=None, metavar="M",
                        help="verify what you will submit: the manifest (JSON, as `swarmdeck submit --manifest` takes) "
                             "gives robots, duration and initial_poses, checked as the portal checks them")
    parser.add_argument("--robots", type=int, default=None, metavar="N",
                        help="declared number of robots: a script whose Arena asks for another number is refused at "
                             "once, as on the portal (default: the manifest's, else the script's own, at most what "
                             "fits in the arena)")
    parser.add_argument("--duration", type=float, default=None, metavar="S",
                        help="declared duration in simulated seconds (default: the manifest's, else 30); each run's "
                             "wall time is bounded by it (--wall-factor)")
    parser.add_argument("--initial-poses", default=None, metavar="FILE",
                        help="start poses as the arena will use them: CSV, one robot per line x,y,theta (m, m, rad); "
                             "default: the manifest's, else the script's initial conditions, else random. Every run "
                             "starts there plus a random set-up error within 2 cm and 5 degrees")
    parser.add_argument("--wall-factor", type=float, default=4.0, metavar="F",
                        help="wall-time budget of each run: 30 s start-up + F x the declared duration (default 4); a "
                             "run that uses it up fails")
    parser.add_argument("--paced-runs", type=int, default=1, metavar="K",
                        help="raw runs that tick in real time (33 ms per tick) like the arena, so timing alone does "
                             "not tell verification apart (default 1)")
    parser.add_argument("--obstacles", default=None, metavar="FILE",
                        help="the arena's line-segment obstacles: a TOML file with [arena] obstacles = [...] (as in "
                             "the console's --config); a robot touching one is a contact")
    parser.add_argument("--runs", type=int, default=None, metavar="K",
                        help="runs per script, each without and with the barrier (default 8; with --epsilon: the fewest "
                             "that can reach it, e.g. 299 for --epsilon 0.01 --confidence 0.95)")
    parser.add_argument("--seed", type=int, default=0, help="base seed of the initial conditions and disturbances (default 0)")
    parser.add_argument("--workers", type=int, default=None, metavar="W", help="local worker processes (default: number of cores)")
    parser.add_argument("--ray", default=None, metavar="auto|ADDRESS|local",
                        help="run on a Ray cluster ('auto': the running one; 'local': start one here); needs swarmdeck[ray]")
    parser.add_argument("--bypass-threshold", type=float, default=0.99, metavar="S",
                        help="safety score every raw run must reach, with no contact, to bypass the barrier (default 0.99)")
    parser.add_argument("--epsilon", type=float, default=None, metavar="EPS",
                        help="the largest P(contact per run) a bypass may have: the report's upper bound on it "
                             "(Clopper-Pearson from the raw runs; the rule of three when none had a contact) above EPS "
                             "refuses the bypass; without --runs, picks the fewest runs with (1-EPS)^n <= 1-confidence "
                             "(those all without contact; each contact needs more runs, and the report says how many)")
    parser.add_argument("--confidence", type=float, default=0.95, metavar="C",
                        help="confidence of the stated bound on P(contact per run), in (0, 1) (default 0.95)")
    parser.add_argument("--falsify-budget", type=int, default=0, metavar="N",
                        help="after the random runs, spend up to N more runs per script (no barrier) searching the "
                             "set-up tolerance (2 cm, 5 degrees) and the tracking noise for the run closest to a "
                             "contact (cross-entropy method); the report gives the worst case found (mm, which "
                             "robots, when) beside the bound, which it never enters; a contact found refuses the "
                             "bypass (default 0: no search)")
    parser.add_argument("--worst-case-dir", default=".", metavar="DIR",
                        help="with --falsify-budget: where the worst case's recording is kept, "
                             "SCRIPT-worst-case.mcap (`swarmdeck play` it; default the current folder)")
    parser.add_argument("--tick-budget", type=float, default=1.0, metavar="S",
                        help="per-tick compute budget of the script: CPU seconds it may use per tick, counted by its "
                             "cgroup (wall seconds where it has none); a tick ends after max(10 x S, S + 5) wall "
                             "seconds whatever it used (default 1.0)")
    parser.add_argument("--trusted", action="store_true",
                        help="run the scripts unconfined where this machine cannot confine them (no jail works)")
    parser.add_argument("--allow-no-cgroup", action="store_true",
                        help="verify even where no cgroup can be created per run (not root, no memory/pids controller): "
                             "then only per-process limits bound a run's memory, processes and CPU")
    parser.add_argument("--jail", choices=("unshare", "bwrap"), default=None,
                        help="confine with this jail only (default: unshare — Linux namespaces around a pre-loaded "
                             "fork server — then bubblewrap)")
    parser.add_argument("--rps", action=argparse.BooleanOptionalAction, default=None,
                        help="resolve `import rps...` to swarmdeck's rps facade (default: when no real rps is installed)")
    from swarmdeck.console.cli.env import add_script_env_argument

    add_script_env_argument(parser)
    parser.add_argument("--json", action="store_true", help="print the JSON report (schema swarmdeck.verification/1)")
    parser.add_argument("--html", default=None, metavar="OUT.html", help="write the HTML report there")


def _declared(args: argparse.Namespace) -> tuple[int | None, float, tuple | None, str, dict | None]:
    """(robots, duration, start poses, who declared the count, the script's parameter values) from --manifest,
    --robots, --duration and --initial-poses (the options win over the manifest; the values are the manifest's
    ``params``, as the portal's verification uses them); UsageError naming what is wrong."""
    from swarmdeck.console.cli import UsageError
    from swarmdeck.console.cli.submit import manifest_from
    from swarmdeck.console.portal.errors import BadInput
    from swarmdeck.console.portal.submission import Limits, parse_manifest
    from swarmdeck.console.runtime.fleet_upkeep import read_poses_csv

    robots, duration, poses, declared_by, params = args.robots, args.duration, None, "--robots", None
    if args.manifest:
        found = manifest_from(argparse.Namespace(manifest=args.manifest, robots=args.robots, duration=args.duration,
                                                 name=None, no_barrier=False, script="verify", param=[]))
        try:  # checked as the portal checks it (its fleet size and maximum duration aside)
            m = parse_manifest(found, Limits(fleet=1 << 20, max_duration=float("inf")))
        except BadInput as exc:
            raise UsageError(f"the manifest {args.manifest!r}: {exc}") from None
        robots, duration, poses = m.robots, m.duration, m.initial_poses
        params = None if m.params is None else dict(m.params)
        declared_by = "--robots" if args.robots is not None else "the manifest"
    if args.initial_poses:
        try:
            poses = tuple((float(x), float(y), float(theta)) for x, y, theta in read_poses_csv(args.initial_poses))
        except ValueError as exc:
            raise UsageError(str(exc)) from None
    return robots, 30.0 if duration is None else duration, poses, declared_by, params


def _runs(args: argparse.Namespace) -> int:
    """Runs per script: --runs, else with --epsilon the fewest that can reach it (REFERENCE.md §17), else 8;
    UsageError naming a bad --runs, --epsilon or --confidence."""
    from swarmdeck.console.cli import UsageError
    from swarmdeck.console.sandbox.guarantee import runs_needed

    if args.runs is not None and args.runs < 1:
        raise UsageError(f"--runs must be >= 1, got {args.runs}")
    try:
        needed = None if args.epsilon is None else runs_needed(args.epsilon, args.confidence)
        if needed is None:
            runs_needed(0.5, args.confidence)  # checks --confidence alone
    except ValueError as exc:
        raise UsageError(f"--epsilon/--confidence: {exc}") from None
    if args.runs is not None:
        if needed is not None and args.runs < needed:
            print(f"note: {args.runs} runs cannot bound P(contact per run) by {args.epsilon:g} at {args.confidence:g} "
                  f"confidence (that needs {needed} runs without contact): no bypass", file=sys.stderr)
        return int(args.runs)
    if needed is not None:
        print(f"{needed} runs per script: the fewest with (1 - {args.epsilon:g})^n <= 1 - {args.confidence:g}",
              file=sys.stderr)
        return needed
    return 8


def _progress(total_runs: int):
    if not sys.stderr.isatty():
        return None, lambda: None
    from tqdm import tqdm

    bar = tqdm(total=total_runs, unit="run", desc="verifying", file=sys.stderr, leave=False)
    return (lambda p: bar.update(1)), bar.close


def main(args: argparse.Namespace) -> int:
    from swarmdeck.console.cli import UsageError
    from swarmdeck.console.cli.env import checked_script_env
    from swarmdeck.console.cli.run import check_run_arguments, obstacles_argument
    from swarmdeck.console.sandbox.confinement import ConfinementUnavailable, JailConfig, SandboxLimits
    from swarmdeck.console.sandbox.executors import LocalPoolExecutor, RayExecutor
    from swarmdeck.console.sandbox.report_html import render_html
    from swarmdeck.console.sandbox.verification import REJECTED, VerificationConfig, verify

    robots, duration, poses, declared_by, params = _declared(args)
    check_run_arguments(robots, duration, seed=args.seed)
    runs = _runs(args)
    if args.workers is not None and args.workers < 1:
        raise UsageError(f"--workers must be >= 1, got {args.workers}")
    if args.falsify_budget < 0:
        raise UsageError(f"--falsify-budget must be >= 0, got {args.falsify_budget}")
    try:
        limits = SandboxLimits(tick_s=args.tick_budget)
        config = VerificationConfig(n_robots=robots, duration=duration, runs=runs, seed=args.seed,
                                    epsilon=args.epsilon, confidence=args.confidence, bypass_threshold=args.bypass_threshold, limits=limits, trusted=args.trusted,
                                    rps=args.rps, jail=JailConfig(order=(args.jail,) if args.jail else JailConfig().order,
                                                                   allow_no_cgroup=args.allow_no_cgroup,
                                                                   script_env=checked_script_env(args.script_env)),
                                    initial_poses=poses, declared_by=declared_by, wall_factor=args.wall_factor,
                                    paced_runs=args.paced_runs, obstacles=obstacles_argument(args),
                                    falsify_budget=args.falsify_budget)
        executor = RayExecutor(args.ray) if args.ray else LocalPoolExecutor(args.workers)
    except (ValueError, RuntimeError) as exc:
        raise UsageError(str(exc)) from exc
    worst_case_dir = None
    if args.falsify_budget:
        worst_case_dir = Path(args.worst_case_dir)
        if not worst_case_dir.is_dir():
            raise UsageError(f"--worst-case-dir {args.worst_case_dir!r} is not a folder")
    on_progress, close = _progress((2 * runs + args.falsify_budget) * len(args.scripts))
    try:
        report = verify(args.scripts, config, executor, on_progress=on_progress, entry=args.entry,
                        worst_case_dir=worst_case_dir, params=params)
    except (ValueError, ConfinementUnavailable) as exc:
        raise UsageError(str(exc)) from exc
    except ConnectionError as exc:
        raise UsageError(f"cannot reach the Ray cluster at {args.ray!r}: {exc}") from exc
    except RuntimeError as exc:  # an executor's infrastructure failed (a Ray worker, a pool process)
        raise UsageError(str(exc)) from exc
    finally:
        close()
    data = report.to_dict()
    if args.html:
        try:
            with open(args.html, "w", encoding="utf-8") as f:
                f.write(render_html(data))
        except OSError as exc:
            raise UsageError(f"cannot write the HTML report {args.html!r}: {exc}") from exc
    if args.json:
        print(json.dumps(data, indent=2))
    else:
        for s in data["scripts"]:
            if s["verdict"] == REJECTED:  # S of runs that failed says nothing: the reasons below do
                print(f"{s['script']}: {s['verdict']}")
            else:
                score = "n/a" if s["safety_score"] is None else f"{s['safety_score']:.4f}"
                print(f"{s['script']}: {s['verdict']} (safety score S = {score} over {runs} runs without the "
                      "barrier)")
            if s.get("contact_bound"):
                print(f"  {s['contact_bound']['statement']}")
            if s.get("falsification"):
                found = s["falsification"]
                where = f": {worst_case_dir / found['recording']}" if found.get("recording") and worst_case_dir else ""
                print(f"  {found['statement']}{where}")
            for reason in s["reasons"]:
                print(f"  rejected: {reason}")
            for reason in s["bypass_refused_because"]:
                print(f"  no bypass: {reason}")
        if args.html:
            print(f"report: {args.html}")
    return 1 if report.verdict == REJECTED else 0
