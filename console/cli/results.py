"""``swarmdeck results JOB -o DIR``: download a job's data (recording, CSV, replay, log, reports)."""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from swarmdeck.console.cli import UsageError
from swarmdeck.console.cli._client import add_client_arguments, client, fail

NAME = "results"
HELP = "download a job's results from the lab's portal: MCAP recording, CSV, HTML replay, script log, reports"
ORDER = 74


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("job", type=int, metavar="JOB", help="the job's id (see swarmdeck jobs)")
    parser.add_argument("-o", "--output", required=True, metavar="DIR", help="folder to write the files to")
    add_client_arguments(parser)


def main(args: argparse.Namespace) -> int:
    from swarmdeck.console.portal.client import ClientError

    out = Path(args.output)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UsageError(f"cannot create {args.output!r}: {exc.strerror or exc}") from None
    written = []
    with client(args) as c:
        try:
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
        print(json.dumps({"job": args.job, "files": written}))
    elif not written:
        print(f"job {args.job} has no results yet")
    return 0
