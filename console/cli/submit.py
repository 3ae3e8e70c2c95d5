"""``swarmdeck submit SCRIPT``: send an experiment to the lab's portal (verified, queued, run on the arena)."""
from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from swarmdeck.console.cli import UsageError
from swarmdeck.console.cli._client import add_client_arguments, client, fail, job_line
from swarmdeck.console.cli._param_option import param_values
from swarmdeck.console.portal.states import JobState

NAME = "submit"
HELP = "submit an experiment script (.py or .zip) to the lab's portal; --wait follows it to the end"
ORDER = 72


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.epilog = ("The manifest is JSON: {\"name\", \"robots\", \"duration\", \"initial_poses\"?, \"no_barrier\"?, "
                     "\"params\"?}; --robots/--duration/--name/--no-barrier/--param build or override it. Exit status: 0 submitted "
                     "(with --wait: the job is done), 1 a server error or (with --wait) the job did not end done, "
                     "2 usage.")
    parser.add_argument("script", metavar="SCRIPT", help="the experiment (.py), or a .zip with it (and manifest.json)")
    parser.add_argument("--manifest", default=None, metavar="M", help="the manifest (JSON file)")
    parser.add_argument("--name", default=None, help="the experiment's name (default: the script's file name)")
    parser.add_argument("--robots", type=int, default=None, metavar="N", help="robots the experiment uses")
    parser.add_argument("--duration", type=float, default=None, metavar="S", help="declared duration, s")
    parser.add_argument("--entry", default=None, metavar="FILE",
                        help="for a .zip: the script inside it to run, e.g. src/main.py (default: the manifest's "
                             "'entry', else main.py, else the archive's only .py file)")
    parser.add_argument("--no-barrier", action="store_true",
                        help="ask to run without the safety barrier: granted only if verification allows it and an "
                             "operator approves this job's bypass (until then it waits); the walls, the docked robots "
                             "and the guard stay on, and the barrier comes back if two robots get too close")
    sweep = parser.add_argument_group("a parameter sweep (one job, run in simulation on the lab's verification "
                                      "workers, never on the arena; see docs/sweeps.md)")
    sweep.add_argument("--sweep", action="store_true",
                       help="submit a sweep of the script's declared parameters instead of an arena run; its "
                            "results: the report, the table and the summary with CIs (swarmdeck results ID)")
    sweep.add_argument("--param", action="append", default=[], metavar="NAME=VALUES",
                       help="with --sweep: a swept parameter (repeat for each), as swarmdeck sweep takes it: "
                            "NAME=0.5:2:4, NAME=log:0.1:10:5, NAME=0.5,1,2; --param robots=2,4 sweeps the robot count. "
                            "Without --sweep: NAME=VALUE, one value of a parameter the script declares, for the "
                            "arena run and its verification (the manifest's params)")
    sweep.add_argument("--promote", default=None, metavar="METRIC[:min|max]",
                       help="with --sweep: when the sweep is done, submit its best point by METRIC (a built-in one: "
                            "min_distance, contacts, barrier_interventions, coverage_cost_H, time_to_goal; or one "
                            "the script records, with :min or :max) as an arena job with that point's values")
    sweep.add_argument("--seeds", type=int, default=None, metavar="K", help="with --sweep: runs per point (default 1)")
    sweep.add_argument("--seed", type=int, default=None, metavar="S",
                       help="with --sweep: the first seed and the random design's seed (default 0)")
    sweep.add_argument("--design", choices=("grid", "random"), default=None, help="with --sweep: grid (default) or random")
    sweep.add_argument("--samples", type=int, default=None, metavar="M", help="with --sweep: points of a random design")
    parser.add_argument("--wait", action="store_true",
                        help="follow the job until it ends (states on stderr), then print its results in short: did "
                             "the barrier step in, the minimum distance, contacts, the files, the download command")
    add_client_arguments(parser)


def manifest_from(args: argparse.Namespace) -> dict | None:
    manifest: dict = {}
    if args.manifest:
        try:
            manifest = json.loads(Path(args.manifest).read_text(encoding="utf-8"))
        except OSError as exc:
            raise UsageError(f"cannot read the manifest {args.manifest!r}: {exc.strerror or exc}") from None
        except ValueError as exc:
            raise UsageError(f"the manifest {args.manifest!r} is not valid JSON: {exc}") from None
        if not isinstance(manifest, dict):
            raise UsageError(f"the manifest {args.manifest!r} must hold a JSON object")
    for key, value in (("robots", args.robots), ("duration", args.duration), ("name", args.name),
                       ("params", param_values(args.param))):
        if value is not None:
            manifest[key] = value
    if args.no_barrier:
        manifest["no_barrier"] = True
    if not manifest and args.script.lower().endswith(".zip"):
        return None  # the archive's manifest.json
    manifest.setdefault("name", Path(args.script).stem)
    return manifest


def sweep_from(args: argparse.Namespace) -> dict:
    """The sweep request (:mod:`swarmdeck.console.portal.sweep_job`) of ``--sweep``'s options; the portal checks it."""
    params = [p for p in args.param if p.partition("=")[0].strip() != "robots"]
    counts = [p.partition("=")[2] for p in args.param if p.partition("=")[0].strip() == "robots"]
    if counts and args.robots is not None:
        raise UsageError("give the robot counts once: --robots N or --param robots=..., not both")
    robots: int | str | None = counts[0] if counts else args.robots
    if robots is None or args.duration is None:
        raise UsageError("a sweep needs the robots and how long each run is: --robots N (or --param robots=...) "
                         "--duration S")
    sweep: dict = {"name": args.name or Path(args.script).stem, "params": params, "robots": robots,
                   "duration": args.duration}
    for key in ("seeds", "seed", "design", "samples"):
        if getattr(args, key) is not None:
            sweep[key] = getattr(args, key)
    if args.no_barrier:
        sweep["no_barrier"] = True
    if args.promote is not None:
        metric, _, goal = args.promote.partition(":")
        sweep["promote"] = {"metric": metric, **({"goal": goal} if goal else {})}
    return sweep


def _submitted(args: argparse.Namespace, c: Any, send: Callable[[], dict], what: str) -> tuple[dict, dict | None]:
    """Submit with ``send()`` and say so (``what``: "job", "sweep job"); with --wait, follow the job to its end and
    fetch its results (None: rejected, results deleted, or not waited for). ClientError from the portal."""
    job = send()
    if not args.json:
        print(f"submitted {what} {job['id']}: {job['state']}")
    results = None
    if args.wait:
        job = c.wait(job["id"], on_state=lambda j: print(job_line(j), file=sys.stderr))
        if job["state"] != JobState.REJECTED and not job.get("results_deleted"):
            results = c.results(job["id"])
    return job, results


def main_sweep(args: argparse.Namespace) -> int:
    """``swarmdeck submit --sweep``: the sweep as one job; with --wait, its summary when it ended."""
    from swarmdeck.console.portal.client import ClientError

    if args.manifest:
        raise UsageError("--manifest is for an arena run; a sweep takes --robots, --duration and --param")
    sweep = sweep_from(args)
    with client(args) as c:
        try:
            job, results = _submitted(args, c, lambda: c.submit_sweep(args.script, sweep, args.entry), "sweep job")
        except ClientError as exc:
            return fail(NAME, exc, args.json)
    if args.json:
        print(json.dumps(job if results is None else {**job, "results": results}))
    elif args.wait:
        print(f"job {job['id']}: {job['state']}" + (f" ({job['reason']})" if job.get("reason") else ""))
        found = (results or {}).get("sweep")
        if found:
            print(f"  {found['runs']} runs, {found['failed']} failed; the report: "
                  f"swarmdeck results {job['id']} -o job{job['id']}/ (sweep-report.html, results.csv, summary.csv)")
    return 0 if not args.wait or job["state"] == JobState.DONE else 1


def main(args: argparse.Namespace) -> int:

    if not Path(args.script).is_file():
        raise UsageError(f"script {args.script!r} does not exist or is not a file")
    if args.entry is not None and not args.script.lower().endswith(".zip"):
        raise UsageError("--entry names the script inside a .zip; a .py is its own entry")
    if args.sweep:
        return main_sweep(args)
    if any(getattr(args, k) is not None for k in ("seeds", "seed", "design", "samples", "promote")):
        raise UsageError("--seeds, --seed, --design, --samples and --promote are for a sweep: add --sweep")
    manifest = manifest_from(args)
    if manifest is not None and ("robots" not in manifest or "duration" not in manifest):
        raise UsageError("say how many robots and for how long: --robots N --duration S (or --manifest M)")
    return submit_job(args, args.script, manifest, args.entry)


def submit_job(args: argparse.Namespace, script: str | Path, manifest: dict | None, entry: str | None,
               command: str = NAME) -> int:
    """Submit ``script`` as an arena job (``manifest``; None: the .zip's own) on the portal of ``args``' client
    options and say so; with --wait follow it to its end and print its results in short; with --json print the job.
    Exit status as ``swarmdeck submit``'s (``swarmdeck train --submit`` too; ``command`` names it in errors)."""
    from swarmdeck.console.portal.client import ClientError

    with client(args) as c:
        try:
            job, results = _submitted(args, c, lambda: c.submit(script, manifest, entry), "job")
        except ClientError as exc:
            return fail(command, exc, args.json)
    if args.json:
        print(json.dumps(job if results is None else {**job, "results": results}))
    elif args.wait:
        from swarmdeck.console.portal.results import summary_lines

        print(f"job {job['id']}: {job['state']}" + (f" ({job['reason']})" if job.get("reason") else ""))
        for line in [] if results is None else summary_lines(results):
            print(f"  {line}")
    return 0 if not args.wait or job["state"] == JobState.DONE else 1
