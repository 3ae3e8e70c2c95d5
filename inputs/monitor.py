"""``swarmdeck inputs monitor``: a live terminal view of input sources, contacts,
message rates and malformed counts — what an operator checks before a run.
The command line is in :mod:`swarmdeck.console.cli.inputs`.
"""
from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable
from typing import TextIO

from .config import InputConfig
from .contact import InputSnapshot
from .hub import InputHub


def _counts(d: dict[str, int]) -> str:
    return ", ".join(f"{k} {v}" for k, v in sorted(d.items())) or "-"


def render(snap: InputSnapshot, listeners: tuple[str, ...] = (), t0: float = 0.0) -> str:
    """A plain-text page describing ``snap``: every source's health, then every
    contact; the header shows ``snap.t - t0`` (time since the monitor started)."""
    lines = [f"swarmdeck inputs monitor   t={snap.t - t0:.1f} s   listening: {', '.join(listeners) or '-'}", ""]
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
            page = render(hub.poll(now), names, t0)
            out.write(("\x1b[H\x1b[2J" if tty else "\n") + page + "\n")
            out.flush()
            if duration is not None and now - t0 >= duration:
                return 0
            time.sleep(interval if duration is None else max(0.0, min(interval, t0 + duration - now)))
