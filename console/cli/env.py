"""``swarmdeck env``: what users' scripts can import — the lab's script environment — and how to make one.

``swarmdeck env`` lists it: with ``--script-env PATH`` that environment; with ``--server URL`` (or
``$SWARMDECK_SERVER``) the portal's (``GET /api/env``); otherwise swarmdeck's own environment.
``swarmdeck env create PATH [--packages P ...]`` makes one that follows the rule
(:mod:`swarmdeck.console.sandbox.script_env`), for ``--script-env PATH`` of ``swarmdeck server``,
``swarmdeck verify`` and ``swarmdeck run --sandbox``.
"""
from __future__ import annotations

import argparse
import json
import os

from swarmdeck.console.cli import UsageError

NAME = "env"
HELP = "list the packages users' scripts can import (the lab's script environment), or create one"
ORDER = 76

SCRIPT_ENV_HELP = ("the lab's script environment: a virtual environment (`swarmdeck env create PATH`) bound read-only "
                   "in the jail; scripts import only its packages besides the standard library, swarmdeck and numpy "
                   "(default: what swarmdeck's own environment has)")


def add_script_env_argument(parser: argparse.ArgumentParser, prefix: str = "") -> None:
    """The ``--script-env PATH`` option of ``server``, ``verify`` and ``run --sandbox``."""
    parser.add_argument("--script-env", default=None, metavar="PATH", help=prefix + SCRIPT_ENV_HELP)


def checked_script_env(path: str | None) -> str | None:
    """``path`` when it names a script environment that follows the rule; UsageError saying what is wrong."""
    if path is None:
        return None
    from swarmdeck.console.sandbox.script_env import ScriptEnv

    try:
        return str(ScriptEnv.open(path).root)
    except ValueError as exc:
        raise UsageError(f"--script-env: {exc}") from None


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from swarmdeck.console.cli._client import add_client_arguments

    parser.add_argument("--script-env", default=None, metavar="PATH",
                        help="list this script environment (what `--script-env PATH` of server/verify/run gives scripts)")
    add_client_arguments(parser)
    sub = parser.add_subparsers(dest="env_action", metavar="ACTION")
    create = sub.add_parser("create", help="create a script environment at PATH (a virtual environment of this Python "
                                           "without the system's packages; numpy pinned to swarmdeck's)",
                            description="Create a script environment: `python -m venv PATH`, then `pip install "
                                        "PACKAGES` with numpy pinned to swarmdeck's version. Add packages later with "
                                        "PATH/bin/pip install NAME (keep it readable by all: chmod -R a+rX PATH).")
    create.add_argument("path", metavar="PATH", help="a new (or empty) folder")
    create.add_argument("--packages", nargs="+", default=[], metavar="P",
                        help="pip requirements to install, e.g. scipy networkx 'torch==2.5.*'")


def main(args: argparse.Namespace) -> int:
    from swarmdeck.console.sandbox.script_env import ScriptEnv, create, format_listing, listing

    if args.env_action == "create":
        try:
            env = create(args.path, args.packages)
        except ValueError as exc:
            raise UsageError(str(exc)) from None
        info = listing(env)
        print(json.dumps(info) if args.json else format_listing(info) +
              f"\nUse it: swarmdeck server --script-env {env.root} (and verify / run --sandbox --script-env).")
        return 0
    if args.script_env is not None or not (args.server or os.environ.get("SWARMDECK_SERVER")):
        try:
            info = listing(None if args.script_env is None else ScriptEnv.open(args.script_env))
        except ValueError as exc:
            raise UsageError(str(exc)) from None
    else:
        from swarmdeck.console.cli._client import client, fail
        from swarmdeck.console.portal.client import ClientError

        with client(args) as c:
            try:
                info = c.env()
            except ClientError as exc:
                return fail(NAME, exc, args.json)
    print(json.dumps(info) if args.json else format_listing(info))
    return 0
