"""``swarmdeck compare A.mcap B.mcap …``: a table of the runs' metrics (issue 31 item 4)."""
from __future__ import annotations

import argparse
import json
import sys

NAME = "compare"
HELP = ("compare recorded runs: duration, robots, contacts, minimum distance, barrier interventions, coverage "
        "cost H, distance travelled … one column per run (--json for scripts); says what differs between them")
ORDER = 62


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("file", nargs="+", help="two or more .mcap recordings (one is summarised alone)")
    parser.add_argument("--json", action="store_true",
                        help="print {runs: [{name, file, duration_s, robots, contacts, min_distance_m, …}], "
                             "differences: [...], metrics: [{key, label}]}")


def main(args: argparse.Namespace) -> int:
    from swarmdeck.console.cli.play import open_runs
    from swarmdeck.console.recording.metrics import comparison, run_letter, run_metrics, table

    runs = open_runs(args.file, warnings=sys.stderr)  # stdout stays the table / the JSON
    try:
        metrics = [run_metrics(r) for r in runs]
    finally:
        for r in runs:
            r.close()
    if args.json:
        print(json.dumps(comparison(metrics), indent=2))
        return 0
    for i, m in enumerate(metrics):
        print(f"{run_letter(i)}: {m.file}" + (" (damaged: the readable part)" if m.warnings else ""))
    print()
    print(table(metrics))
    result = comparison(metrics)
    if result["differences"]:
        print()
        for line in result["differences"]:
            print(f"note: {line}")
    return 0
