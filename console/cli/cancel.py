"""``swarmdeck cancel JOB``: cancel one of your jobs on the lab's portal (awaiting verification, verifying, awaiting approval, in arena queue or running)."""
from __future__ import annotations

import argparse
import json

from swarmdeck.console.cli._client import add_client_arguments, client, fail

NAME = "cancel"
HELP = "cancel one of your jobs on the lab's portal (a running job stops within a tick, robots stopped)"
ORDER = 75


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("job", type=int, metavar="JOB", help="the job's id (see swarmdeck jobs)")
    add_client_arguments(parser)


def main(args: argparse.Namespace) -> int:
    from swarmdeck.console.portal.client import ClientError

    with client(args) as c:
        try:
            job = c.cancel(args.job)
        except ClientError as exc:
            return fail(NAME, exc, args.json)
    print(json.dumps(job) if args.json else f"job {job['id']}: {job['state']}")
    return 0
