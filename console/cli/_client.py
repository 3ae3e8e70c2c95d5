"""What the portal's client commands (``submit``, ``jobs``, ``results``, ``cancel``) share: options and the client.

Not a command (the leading underscore keeps it out of discovery). Token from
``--token`` or ``SWARMDECK_TOKEN``; server from ``--server`` or ``SWARMDECK_SERVER``.
Server errors are one line on stderr and exit status 1; usage errors exit 2.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
from typing import Any

from swarmdeck.console.cli import UsageError


def add_client_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--server", default=None, metavar="URL",
                        help="the lab's portal, e.g. https://arena.example.org (default: $SWARMDECK_SERVER)")
    parser.add_argument("--token", default=None, help="your access token (default: $SWARMDECK_TOKEN)")
    parser.add_argument("--json", action="store_true", help="print one JSON object (for scripts)")


def client(args: argparse.Namespace) -> Any:
    from swarmdeck.console.portal.client import PortalClient

    url = args.server or os.environ.get("SWARMDECK_SERVER")
    token = args.token or os.environ.get("SWARMDECK_TOKEN")
    if not url:
        raise UsageError("say which server: --server URL (or set SWARMDECK_SERVER)")
    if not token:
        raise UsageError("no access token: --token TOKEN (or set SWARMDECK_TOKEN)")
    try:
        return PortalClient(url, token)
    except ValueError as exc:
        raise UsageError(str(exc)) from None


def fail(command: str, exc: Any, as_json: bool) -> int:
    """Report a server error (ClientError) as one line (or one JSON object); exit status 1."""
    if as_json:
        print(json.dumps({"error": exc.message, "field": exc.field, "status": exc.status}))
    print(f"swarmdeck {command}: error: {exc.line()}", file=sys.stderr)
    return 1


def shorten(text: str, width: int) -> str:
    """``text`` on one line, at most ``width`` characters, cut at a word boundary with "…" (never mid-word)."""
    text = " ".join(text.split())
    if len(text) <= width:
        return text
    cut = text[: width - 1]
    space = cut.rfind(" ")
    return (cut[:space] if space > width // 2 else cut).rstrip(" ,;:") + "…"


def _clock(t: float) -> str:
    """A time as ``HH:MM`` UTC (``MM-DD HH:MM`` when not today)."""
    import time

    now, then = time.gmtime(), time.gmtime(t)
    return time.strftime("%H:%M" if then[:3] == now[:3] else "%m-%d %H:%M", then)


def job_line(job: dict[str, Any]) -> str:
    """One job as ``swarmdeck jobs`` lists it (queue positions counted from 1, as on the pages)."""
    extra = ""
    if job.get("verdict"):
        extra += f"  [{job['verdict']}]"
    if job.get("position") is not None:
        extra += f"  (queue position {job['position'] + 1})"
    if job.get("eta_start") is not None:
        extra += f"  starts ~{_clock(job['eta_start'])}, ends ~{_clock(job['eta_end'])} UTC on {job['eta_arena']}"
    elif job.get("placed"):
        extra += f"  on {job['placed']}"
    if job.get("reason"):
        extra += f"  {shorten(job['reason'], 200)}"
    if job.get("results_deleted"):
        extra += "  (results deleted: retention)"
    return f"{job['id']:>5}  {job['state']:<21}  {job['name'][:40]:<40}  {job['robots']:>3} robots  " \
           f"{job['duration']:g} s{extra}"
