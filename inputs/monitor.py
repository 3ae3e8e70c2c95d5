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

#: Rows of the page: sources and contacts beyond these are summarised in one line each.
MAX_SOURCE_ROWS = 20
MAX_CONTACT_ROWS = 20
WIDTH = 150  # longest line; longer texts (a hostile sender's error details) are cut


def _counts(d: dict[str, int]) -> str:
    return ", ".join(f"{k} {v}" for k, v in sorted(d.items())) or "-"


_CONTROL = {c: " " for c in [*range(32), 127]}


def _cut(text: str, width: int = WIDTH) -> str:
    text = text.translate(_CONTROL)  # no line breaks or terminal escapes from a sender
    return text if len(text) <= width else text[:width - 1] + "…"


def _row(h, now: float) -> str:
    age = now - h.last_seen if math.isfinite(h.last_seen) else math.inf
    state = "LOST" if h.lost else ("ok" if age < 1.0 else "quiet")
    return _cut(f"{h.name[:48]:<48} {h.kind:<8} {h.rate_hz:>7.1f} {age:>6.1f} {h.contacts:>4}  {state:<6}  "
                f"E: {_counts(h.errors)} | W: {_counts(h.warnings)}")


def render(snap: InputSnapshot, listeners: tuple[str, ...] = (), t0: float = 0.0,
           max_sources: int = MAX_SOURCE_ROWS, max_contacts: int = MAX_CONTACT_ROWS) -> str:
    """A plain-text page describing ``snap``: each listener's lifetime totals, then at
    most ``max_sources`` sources (those with contacts first, then the most recently
    heard) and ``max_contacts`` contacts, the rest summarised; the header shows
    ``snap.t - t0`` (time since the monitor started). At most ~60 lines of at most
    ``WIDTH`` characters whatever arrived."""
    now = snap.t
    lines = [_cut(f"swarmdeck inputs monitor   t={now - t0:.1f} s   listening: {', '.join(listeners) or '-'}"), ""]
    lines.append(f"{'source':<48} {'kind':<8} {'rate/s':>7} {'age s':>6} {'cont':>4}  state   errors / warnings")
    totals = [h for h in snap.health if h.kind == "listener"]
    sources = [h for h in snap.health if h.kind not in ("listener", "more")]
    not_reported = sum(int(h.name.rsplit(": ", 1)[-1].split()[0]) for h in snap.health if h.kind == "more")
    for h in totals:
        lines.append(_row(h, now))
        if h.last_error:
            lines.append(_cut(f"{'':<10}last error: {h.last_error}"))
    if not sources and not any(h.datagrams for h in totals):
        lines.append("  (nothing received yet — is the sender pointed at this host and port?)")
    sources.sort(key=lambda h: (h.contacts == 0, -h.last_seen))
    for h in sorted(sources[:max_sources], key=lambda h: h.name):
        lines.append(_row(h, now))
        if h.last_error:
            lines.append(_cut(f"{'':<10}last error: {h.last_error}"))
    hidden = len(sources) - min(len(sources), max_sources) + not_reported
    if hidden:
        lines.append(f"  … {hidden} more sources not shown (the listener totals above count all their "
                     "datagrams, errors and warnings)")
    lines.append("")
    lines.append(f"contacts ({len(snap.contacts)}):")
    for c in snap.contacts[:max_contacts]:
        extra = f" size {c.size:.3f} m" if c.size is not None else ""
        lines.append(_cut(f"  {c.source[-40:]:<40} id {c.id:<5} {c.kind:<7} x {c.position[0]:+.3f} "
                          f"y {c.position[1]:+.3f} m  v {c.velocity[0]:+.2f} {c.velocity[1]:+.2f} m/s{extra}"))
    rest = snap.contacts[max_contacts:]
    if rest:
        per: dict[str, int] = {}
        for c in rest:
            per[c.source] = per.get(c.source, 0) + 1
        top = sorted(per.items(), key=lambda kv: -kv[1])[:5]
        lines.append(_cut(f"  … {len(rest)} more contacts (by source: "
                          + ", ".join(f"{name.split('://', 1)[-1][-28:]} {n}" for name, n in top)
                          + (f", … {len(per) - 5} more sources" if len(per) > 5 else "") + ")"))
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
