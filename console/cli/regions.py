"""``swarmdeck regions LAYOUT [--run REGION=SCRIPT ...]``: several experiments at once on one floor.

LAYOUT is a TOML file with a ``[regions]`` table (one sub-table per region: ``bounds`` in floor metres,
``chargers``: the floor walls whose strips it docks on; optional ``[floor] bounds``) or ``COLSxROWS`` (equal
regions, e.g. ``2x2``). Without ``--run`` it checks the layout and prints each region with the robots it holds
(what the lab's scheduler asks: :meth:`~swarmdeck.devices.fleet.regions.RegionLayout.capacity`). With ``--run``
it runs the scripts at once on a simulated floor, each unmodified in its region (its region is its arena), every
robot certified by the floor's one barrier, and prints each job's result and what the floor measured.
"""
from __future__ import annotations

import argparse
import functools
import json
import re
from pathlib import Path
from typing import Any

from swarmdeck.console.cli import UsageError

NAME = "regions"
HELP = "several experiments at once on one floor: check a region layout, or run scripts in its regions (simulated)"
ORDER = 63


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("layout", metavar="LAYOUT",
                        help="a TOML file with a [regions] table (and optionally [floor] bounds = [x0, x1, y0, y1]), "
                             "or COLSxROWS for equal regions, e.g. 2x2, or auto:COLSxROWS for regions allocated per "
                             "job (the floor's guillotine cuts down to that grid: a job gets the smallest that holds "
                             "its robots)")
    parser.add_argument("--run", action="append", default=[], metavar="REGION=SCRIPT",
                        help="run SCRIPT (unmodified) in REGION; repeat for several jobs at once")
    parser.add_argument("--robots", type=int, default=4, metavar="N", help="robots of each job (default %(default)s)")
    parser.add_argument("--parked", type=int, default=None, metavar="K",
                        help="simulated robots parked in each region (default: --robots)")
    parser.add_argument("--duration", type=float, default=10.0, metavar="S",
                        help="each job's duration, s of floor time (default %(default)s)")
    parser.add_argument("--seed", type=int, default=None, help="seed of the jobs' random start poses")
    parser.add_argument("--json", action="store_true", help="print the result as JSON")


def load_layout(spec: str) -> Any:
    """The :class:`~swarmdeck.devices.fleet.regions.RegionLayout` of ``spec`` (a TOML file, COLSxROWS, or
    ``auto:COLSxROWS`` — regions allocated per job, :meth:`~swarmdeck.devices.fleet.regions.RegionLayout.guillotine`);
    UsageError naming what is wrong."""
    from swarmdeck.core.bounds import DEFAULT_BOUNDS, check_bounds
    from swarmdeck.core.config import read_toml
    from swarmdeck.devices.fleet.regions import RegionLayout

    grid = re.fullmatch(r"(auto:)?(\d+)x(\d+)", spec.strip())
    try:
        if grid:
            build = RegionLayout.guillotine if grid.group(1) else RegionLayout.grid
            return build(DEFAULT_BOUNDS, int(grid.group(2)), int(grid.group(3)))
        data = read_toml(spec, error=UsageError)
        floor = data.get("floor", {}).get("bounds", DEFAULT_BOUNDS) if isinstance(data.get("floor"), dict) \
            else DEFAULT_BOUNDS
        return RegionLayout.from_mapping(data.get("regions", {}), check_bounds(floor, "[floor] bounds"))
    except ValueError as exc:
        raise UsageError(f"{spec}: {exc}") from None


def main(args: argparse.Namespace) -> int:
    layout = load_layout(args.layout)
    if not args.run:
        out = layout.to_dict()
        if args.json:
            print(json.dumps(out, indent=2))
        else:
            for r in layout.regions:
                print(f"{r.name:12s} bounds {tuple(round(v, 3) for v in r.bounds)}  chargers "
                      f"{', '.join(r.chargers) or '-':24s} holds {out['capacity'][r.name]} robots")
        return 0
    jobs: dict[str, Path] = {}
    for item in args.run:
        region, sep, script = item.partition("=")
        if not sep or region not in layout.names:
            raise UsageError(f"--run {item}: use REGION=SCRIPT with REGION one of {', '.join(layout.names)}")
        if region in jobs:
            raise UsageError(f"--run {item}: region {region} already runs {jobs[region]}")
        if not Path(script).is_file():
            raise UsageError(f"--run {item}: no file {script}")
        jobs[region] = Path(script)
    if args.robots < 1 or not args.duration > 0:
        raise UsageError("--robots must be >= 1 and --duration > 0")
    return _run(layout, jobs, args)


def _run(layout: Any, jobs: dict[str, Path], args: argparse.Namespace) -> int:
    from swarmdeck.console.runtime.region_jobs import RegionJobResult, run_in_region
    from swarmdeck.core.service_thread import ServiceThread
    from swarmdeck.devices.fleet.floor import simulated_floor

    try:
        floor = simulated_floor(layout, {name: (args.parked or args.robots) if name in jobs else 0
                                         for name in layout.names})
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    results: dict[str, RegionJobResult] = {}

    def job(region: str, path: Path) -> None:
        results[region] = run_in_region(floor, region, path, n_robots=args.robots, duration=args.duration,
                                        seed=args.seed)

    threads = [ServiceThread(functools.partial(job, *item), f"swarmdeck-region-{item[0]}", join_timeout=None)
               for item in jobs.items()]
    for t in threads:
        t.start()
    for t in threads:
        t.stop()  # joins: each job ends with its duration
    out: dict[str, Any] = {"floor": floor.stats.to_dict(), "contacts": int(floor.ports.report.collision_pairs),
                           "jobs": {}}
    failed = False
    for region, r in results.items():
        error = r.error or (r.run.error_line if r.run is not None else None)
        failed |= error is not None
        out["jobs"][region] = {"script": str(jobs[region]), "robots": r.fleet_ids, "setup": r.setup,
                               "return": r.returned, "error": error,
                               "returned": None if r.run is None else _plain(r.run.returned)}
    if args.json:
        print(json.dumps(out, indent=2))
    else:
        for region, j in out["jobs"].items():
            print(f"{region}: {j['script']} on floor robots {j['robots']}: "
                  f"{'FAILED: ' + j['error'] if j['error'] else 'done'}; set-up {j['setup'].get('seconds')} s, "
                  f"return {j['return'].get('seconds')} s" + (f"; returned {j['returned']}" if j['returned'] else ""))
        f = out["floor"]
        print(f"floor: {f['ticks']} ticks, robots outside their region {f['outside']}, contacts {out['contacts']}, "
              f"closest robots of different regions {f['min_between_regions_m']} m")
    return 1 if failed else 0


def _plain(value: Any) -> Any:
    """``value`` as JSON can hold it (a script's return value may hold numpy numbers)."""
    try:
        return json.loads(json.dumps(value, default=lambda v: v.tolist() if hasattr(v, "tolist") else str(v)))
    except (TypeError, ValueError):
        return str(value)
