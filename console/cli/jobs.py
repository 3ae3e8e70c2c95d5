"""``swarmdeck jobs``: your jobs on the lab's portal, newest first."""
from __future__ import annotations

import argparse
import json

from swarmdeck.console.cli._client import add_client_arguments, client, fail, job_line

NAME = "jobs"
HELP = "list your jobs on the lab's portal (state, verdict, queue position)"
ORDER = 73


def add_arguments(parser: argparse.ArgumentParser) -> None:
    add_client_arguments(parser)


def main(args: argparse.Namespace) -> int:
    from swarmdeck.console.portal.client import ClientError

    with client(args) as c:
        try:
            jobs = c.jobs()
        except ClientError as exc:
            return fail(NAME, exc, args.json)
    if args.json:
        print(json.dumps(jobs))
    else:
        for job in jobs:
            print(job_line(job))
        if not jobs:
            print("no jobs yet: swarmdeck submit SCRIPT --robots N --duration S")
    return 0
