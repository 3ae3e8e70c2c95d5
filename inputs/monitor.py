"""``swarmdeck inputs monitor``: a live terminal view of input sources, contacts,
message rates and malformed counts — what an operator checks before a run.

The command module (``console/commands/inputs.py``) only forwards to
:func:`add_arguments` and :func:`main`; ``python -m swarmdeck.inputs.monitor``
runs the same thing.
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from collections.abc import Callable
from typing import TextIO

from .config import ConfigError, InputConfig, ListenerConfig
from .contact import InputSnapshot
from .hub import InputHub

NAME = "inputs"
HELP = "check input devices: `swarmdeck inputs monitor [--port 3333]` shows TUIO/OSC sources, contacts and errors live"


def _counts(d: dict[str, int]) -> str:
    return ", ".join(f"{k} {v}" for k, v in sorted(d.items())) or "-"


def render(snap: InputSnapshot, listeners: tuple[str, ...] = ()) -> str:
    """A plain-text page describing ``snap`` (sources, then contacts, then recent events)."""
    lines = [f"swarmdeck inputs monitor   t={snap.t:.2f} s   listening: {', '.join(listeners) or '-'}", ""]
    lines.append(f"{'source':<48} {'kind':<6} {'rate/s':>7} {'age s':>6} {'cont':>4}  state   errors / warnings")
    if not snap.health:
        lines.append("  (nothing received yet — is the sender pointed at this host and port?)")
    for h in snap.health:
        age = snap.t - h.last_seen if math.isfinite(h.last_seen) else math.inf
        state = "LOST" if h.lost else ("ok" if age < 1.0 else "quiet")
        lines.append(f"{h.name[:48]:<48} {h.kind:<6} {h.rate_hz:>7.1f} {age:>6.1f} {h.contacts:>4}  {state:<6}  "
                     f"E: {_counts(h.errors)} | W: {_counts(h.warnings)}")
        if h.last_error:
            lines.append(f"{'':<10}last error: {h.last_error}")
    lines.append("")
    lines.append(f"contacts ({len(snap.contacts)}):")
    for c in snap.contacts:
        extra = f" size {c.size:.3f} m" if c.size is not None else ""
        lines.append(f"  {c.source[-40:]:<40} id {c.id:<5} {c.kind:<7} x {c.position[0]:+.3f} y {c.position[1]:+.3f} m"
                     f"  v {c.velocity[0]:+.2f} {c.velocity[1]:+.2f} m/s{extra}")
    return "\n".join(lines)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``swarmdeck inputs``."""
    parser.add_argument("action", nargs="?", default="monitor", choices=["monitor"],
                        help="what to do (monitor: live view of sources and contacts)")
    parser.add_argument("--port", type=int, default=None, help="UDP/TCP port to listen on (default 3333, or the preset's)")
    parser.add_argument("--host", default="127.0.0.1", help="address to bind (0.0.0.0 for a tablet on the network)")
    parser.add_argument("--tcp", action="store_true", help="TUIO/TCP (4-byte length framing) instead of UDP")
    parser.add_argument("--preset", default="tuio", help="tuio, manososc, leap-osc or ultraleap-osc-sender")
    parser.add_argument("--config", default=None, help="TOML file with an [inputs] table (overrides the options above)")
    parser.add_argument("--timeout", type=float, default=1.0, help="s of silence before a source's contacts are lost")
    parser.add_argument("--interval", type=float, default=0.5, help="s between screen updates")
    parser.add_argument("--duration", type=float, default=None, help="stop after this many seconds (default: until Ctrl-C)")


def config_from_args(args: argparse.Namespace) -> InputConfig:
    """The :class:`InputConfig` the options describe; ``ConfigError`` on bad values."""
    if args.config:
        return InputConfig.load_toml(args.config)
    over: dict = {"host": args.host, "timeout": args.timeout, "transport": "tcp" if args.tcp else "udp"}
    if args.port is not None:
        over["port"] = args.port
    return InputConfig(listeners=(ListenerConfig.from_preset(args.preset, **over),))


def run(config: InputConfig, *, duration: float | None = None, interval: float = 0.5, out: TextIO = sys.stdout,
        clock: Callable[[], float] = time.monotonic) -> int:
    """Listen as ``config`` says and print a page every ``interval`` s."""
    hub = InputHub.from_config(config, clock=clock)
    tty = out.isatty()
    t0 = clock()
    with hub:
        names = tuple(f"{s.config.transport}://{s.address[0]}:{s.address[1]}" for s in hub.sources)  # type: ignore[attr-defined]
        print(f"listening on {', '.join(names)}", file=out, flush=True)
        while True:
            now = clock()
            page = render(hub.poll(now), names)
            out.write(("\x1b[H\x1b[2J" if tty else "\n") + page + "\n")
            out.flush()
            if duration is not None and now - t0 >= duration:
                return 0
            time.sleep(interval if duration is None else max(0.0, min(interval, t0 + duration - now)))


def main(args: argparse.Namespace) -> int:
    """Entry point of ``swarmdeck inputs``."""
    try:
        from swarmdeck.console.cli import UsageError
    except ImportError:  # pragma: no cover - console is part of the package
        UsageError = ValueError  # type: ignore[misc,assignment]
    if args.interval <= 0:
        raise UsageError(f"--interval must be > 0 s, got {args.interval}")
    try:
        cfg = config_from_args(args)
    except ConfigError as exc:
        raise UsageError(str(exc)) from None
    try:
        return run(cfg, duration=args.duration, interval=args.interval)
    except OSError as exc:
        raise UsageError(str(exc)) from None


if __name__ == "__main__":  # pragma: no cover
    p = argparse.ArgumentParser(prog="python -m swarmdeck.inputs.monitor", description=HELP)
    add_arguments(p)
    try:
        sys.exit(main(p.parse_args()))
    except KeyboardInterrupt:
        sys.exit(130)
    except Exception as exc:  # UsageError
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)
