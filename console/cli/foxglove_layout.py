"""``swarmdeck foxglove-layout [-o FILE]``: write the Foxglove layout shipped with swarmdeck."""
from __future__ import annotations

import argparse
import sys
from importlib.resources import files

from swarmdeck.console.cli import UsageError

NAME = "foxglove-layout"
HELP = "write the Foxglove layout for swarmdeck recordings and live runs (3D arena, plots, log, camera)"
ORDER = 66


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("-o", "--output", default=None, metavar="FILE",
                        help="where to write it (default: print to stdout); import it in Foxglove with "
                             "Layouts -> Import from file")


def layout_text() -> str:
    """The shipped layout (Foxglove's exported-layout JSON)."""
    return files("swarmdeck.console.recording").joinpath("foxglove_layout.json").read_text(encoding="utf-8")


def main(args: argparse.Namespace) -> int:
    text = layout_text()
    if args.output is None:
        sys.stdout.write(text)
        return 0
    try:
        with open(args.output, "w", encoding="utf-8") as fh:
            fh.write(text)
    except OSError as exc:
        raise UsageError(f"cannot write {args.output}: {exc.strerror or exc}") from None
    print(f"wrote {args.output}: import it in Foxglove with Layouts -> Import from file", file=sys.stderr)
    return 0
