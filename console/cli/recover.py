"""``swarmdeck recover FILE [-o OUT]``: rewrite a recording that was not closed cleanly into a valid MCAP file."""
from __future__ import annotations

import argparse
import sys

from swarmdeck.console.cli import UsageError

NAME = "recover"
HELP = ("rewrite a recording that was not closed cleanly (kill -9, power cut) or is damaged into a valid, indexed "
        "MCAP file holding exactly what `swarmdeck play` plays of it")
ORDER = 63


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("file", help="the damaged .mcap recording (only read, never modified)")
    parser.add_argument("-o", "--output", default=None, metavar="OUT",
                        help="where to write the recovered file (default: FILE's name with .recovered.mcap)")


def main(args: argparse.Namespace) -> int:
    from swarmdeck.console.recording.recover import RecoveryError, recover

    try:
        report = recover(args.file, args.output)
    except RecoveryError as exc:
        raise UsageError(str(exc)) from None
    print(report.summary(), file=sys.stderr)
    print(report.output)
    return 0
