"""The ``swarmdeck`` command line.

Every subcommand lives in its own module under :mod:`swarmdeck.console.cli`
and is discovered at start-up, so subsystems add commands without editing a
shared file. A command module defines::

    NAME: str                      # the subcommand word, e.g. "run"
    HELP: str                      # one line for `swarmdeck --help`
    def add_arguments(parser: argparse.ArgumentParser) -> None: ...
    def main(args: argparse.Namespace) -> int: ...   # exit code

Errors the user caused (bad file, bad option value) are raised as
:class:`UsageError` and printed as one line without a traceback.
"""
from __future__ import annotations

import os

from swarmdeck.core.errors import SwarmdeckError

# The control loop's matrices are small: multi-threaded BLAS only adds contention with
# the loop, viser and camera threads (measured: 0.1 ms single-threaded vs 21 ms
# threaded for one density evaluation on a busy 2-core machine). Set before numpy loads.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import importlib  # noqa: E402
import pkgutil  # noqa: E402
import sys  # noqa: E402
from collections.abc import Sequence  # noqa: E402


class UsageError(SwarmdeckError):
    """A mistake in the command line or in a file the user named."""


def _command_modules(only: str | None = None) -> list[str]:
    """The command modules' names (module ``foo_bar`` is command ``foo-bar``); ``only``: just that command's
    module, when it exists (so ``swarmdeck jobs`` imports the ``jobs`` module and not the console's)."""
    names = [info.name for info in pkgutil.iter_modules(__path__) if not info.name.startswith("_") and not info.ispkg]
    if only is not None and only.replace("-", "_") in names:
        return [only.replace("-", "_")]
    return names


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """Build the top-level parser with every discovered subcommand (``command``: only that one, when it
    exists — a thin command then imports only what it uses)."""
    parser = argparse.ArgumentParser(
        prog="swarmdeck",
        description="Operator console and runtime for a Robotarium-style multi-robot arena.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    modules = [importlib.import_module(f"{__name__}.{name}") for name in _command_modules(command)]
    for module in sorted(modules, key=lambda m: getattr(m, "ORDER", 50)):
        p = sub.add_parser(module.NAME, help=module.HELP, description=module.HELP)
        module.add_arguments(p)
        p.set_defaults(_main=module.main)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``swarmdeck`` command; returns the exit code."""
    try:
        code = _main(argv)
        sys.stdout.flush()  # a closed pipe (`swarmdeck jobs | head -2`) shows here, not at exit
        return code
    except BrokenPipeError:
        # the reader went away (head, less): stop quietly, as Unix tools do; nothing more can be written
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 141  # 128 + SIGPIPE, what a shell reports for a tool ended by a closed pipe


def _main(argv: Sequence[str] | None) -> int:
    words = list(sys.argv[1:] if argv is None else argv)
    rest = None
    if "--" in words:  # `swarmdeck run SCRIPT.py [options] -- ARGS`: ARGS are the script's, whatever they look like
        i = words.index("--")
        words, rest = words[:i], words[i + 1:]
    first = next((w for w in words if not w.startswith("-")), None)  # the top-level parser has no options but -h
    parser = build_parser(first)
    args = parser.parse_args(words)
    if rest is not None:
        if not hasattr(args, "script_args"):
            parser.error(f"unrecognized arguments: -- {' '.join(rest)}")
        args.script_args = [*args.script_args, *rest]
    if not getattr(args, "_main", None):
        parser.print_help()
        return 2
    try:
        return int(args._main(args) or 0)
    except UsageError as exc:
        print(f"swarmdeck {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"swarmdeck {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
