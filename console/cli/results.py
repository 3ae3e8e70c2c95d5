"""``swarmdeck results JOB -o DIR [--no-wait]``: download a job's data (recording, CSV, replay, video, log, reports)."""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from swarmdeck.console.cli import UsageError
from swarmdeck.console.cli._client import add_client_arguments, client, fail
from swarmdeck.console.portal.job import ExportState

NAME = "results"
HELP = ("download a job's results from the lab's portal: MCAP recording, CSV, HTML replay, video, script log, "
        "reports (waits while the exports are still being written)")
ORDER = 74


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("job", type=int, metavar="JOB", help="the job's id (see swarmdeck jobs)")
    parser.add_argument("-o", "--output", required=True, metavar="DIR", help="folder to write the files to")
    parser.add_argument("--no-wait", action="store_true",
                        help="while the job's exports (CSV, HTML replay, video) are still being written, download "
                             "what is ready now instead of waiting for them")
    parser.add_argument("--timeout", type=float, default=600.0, metavar="S",
                        help="wait at most S seconds for the exports (default 600)")
    add_client_arguments(parser)


def main(args: argparse.Namespace) -> int:
    from swarmdeck.console.portal.client import ClientError

    if not args.timeout > 0:
        raise UsageError(f"--timeout must be > 0 s, got {args.timeout}")
    out = Path(args.output)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UsageError(f"cannot create {args.output!r}: {exc.strerror or exc}") from None
    written = []
    with client(args) as c:
        try:
            job = c.job(args.job)
            if job.get("exports") == ExportState.WRITING:
                if args.no_wait:
                    print(f"job {args.job}: exports still being written (CSV, HTML replay, video): downloading what "
                          "is ready; run again later for the rest", file=sys.stderr)
                else:
                    print(f"job {args.job}: exports still being written (CSV, HTML replay, video): waiting "
                          "(--no-wait: download what is ready now)", file=sys.stderr)
                    job = c.wait_exports(args.job, timeout=args.timeout)
            for f in c.files(args.job):
                size = c.download(args.job, f["name"], out / f["name"])
                written.append({"name": f["name"], "path": str(out / f["name"]), "bytes": size})
                if not args.json:
                    print(f"{out / f['name']}  ({size} bytes: {f['what']})")
        except ClientError as exc:
            return fail(NAME, exc, args.json)
        except OSError as exc:
            raise UsageError(f"cannot write to {args.output!r}: {exc.strerror or exc}") from None
    if args.json:
        print(json.dumps({"job": args.job, "exports": job.get("exports"), "files": written}))
    elif not written:
        print(f"job {args.job} has no results yet")
    return 0
