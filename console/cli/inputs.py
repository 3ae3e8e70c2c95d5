"""``swarmdeck inputs monitor|send`` (the console's command module forwards here).

* ``monitor``: a live terminal view of input sources, contacts, message rates
  and malformed counts — what an operator checks before a run.
* ``send``: a synthetic TUIO sender (circling, pinching fingers) to check a
  console or a monitor without a tablet.

``python -m swarmdeck.console.cli.inputs`` runs the same thing.
"""
from __future__ import annotations

import argparse
import sys

from swarmdeck.inputs import monitor, sender
from swarmdeck.inputs.config import ConfigError, InputConfig, ListenerConfig

NAME = "inputs"
ORDER = 40
HELP = "touch/gesture inputs: `monitor` shows TUIO/OSC sources, contacts and errors live; `send` sends demo TUIO"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``swarmdeck inputs``."""
    parser.add_argument("action", nargs="?", default="monitor", choices=["monitor", "send"],
                        help="monitor: live view of sources and contacts; send: demo TUIO fingers")
    parser.add_argument("--port", type=int, default=None, help="port to listen on / send to (default 3333, or the preset's)")
    parser.add_argument("--host", default="127.0.0.1",
                        help="monitor: address to bind (0.0.0.0 for a tablet on the network); send: destination")
    parser.add_argument("--tcp", action="store_true", help="TUIO/TCP (4-byte length framing) instead of UDP")
    parser.add_argument("--preset", default="tuio", help="monitor: tuio, manososc, leap-osc or ultraleap-osc-sender")
    parser.add_argument("--config", default=None, help="monitor: TOML file with an [inputs] table (overrides the options above)")
    parser.add_argument("--timeout", type=float, default=1.0, help="monitor: s of silence before a source's contacts are lost")
    parser.add_argument("--interval", type=float, default=0.5, help="monitor: s between screen updates")
    parser.add_argument("--duration", type=float, default=None,
                        help="stop after this many seconds (monitor default: until Ctrl-C; send default: 10)")
    parser.add_argument("--rate", type=float, default=60.0, help="send: frames per second")
    parser.add_argument("--fingers", type=int, default=2, help="send: number of fingers (2 also pinch)")


def config_from_args(args: argparse.Namespace) -> InputConfig:
    """The monitor's :class:`InputConfig` from the options; ``ConfigError`` on bad values."""
    if args.config:
        return InputConfig.load_toml(args.config)
    over: dict = {"host": args.host, "timeout": args.timeout, "transport": "tcp" if args.tcp else "udp"}
    if args.port is not None:
        over["port"] = args.port
    return InputConfig(listeners=(ListenerConfig.from_preset(args.preset, **over),))


def main(args: argparse.Namespace) -> int:
    """Entry point of ``swarmdeck inputs``."""
    try:
        from swarmdeck.console.cli import UsageError
    except ImportError:  # pragma: no cover - console is part of the package
        UsageError = ValueError  # type: ignore[misc,assignment]
    if args.action == "send":
        try:
            n = sender.run(args.host, args.port if args.port is not None else 3333,
                           duration=10.0 if args.duration is None else args.duration,
                           rate=args.rate, fingers=args.fingers, tcp=args.tcp)
        except (ValueError, OSError) as exc:
            raise UsageError(str(exc)) from None
        print(f"sent {n} TUIO frames to {'tcp' if args.tcp else 'udp'}://{args.host}:{args.port or 3333}")
        return 0
    if args.interval <= 0:
        raise UsageError(f"--interval must be > 0 s, got {args.interval}")
    try:
        cfg = config_from_args(args)
    except ConfigError as exc:
        raise UsageError(str(exc)) from None
    try:
        return monitor.run(cfg, duration=args.duration, interval=args.interval)
    except OSError as exc:
        raise UsageError(str(exc)) from None


if __name__ == "__main__":  # pragma: no cover
    p = argparse.ArgumentParser(prog="python -m swarmdeck.console.cli.inputs", description=HELP)
    add_arguments(p)
    try:
        sys.exit(main(p.parse_args()))
    except KeyboardInterrupt:
        sys.exit(130)
    except Exception as exc:  # UsageError
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)
