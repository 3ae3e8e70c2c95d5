"""``swarmdeck sessions [DIR]``: list recorded sessions."""
from __future__ import annotations

import argparse
import datetime as dt
import os
from pathlib import Path

from swarmdeck.console.cli import UsageError

NAME = "sessions"
HELP = "list recorded sessions in a folder (default sessions/): start, duration, robots, size"
ORDER = 61


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("dir", nargs="?", default="sessions", help="folder of .mcap recordings (default: sessions)")


def list_sessions(directory: str | os.PathLike[str]) -> list[dict]:
    """One dict per ``*.mcap`` file, newest first: file, start, duration_s, robots, size_bytes, state."""
    from swarmdeck.console.recording.reader import RecordingError, open_recording

    rows = []
    for p in sorted(Path(directory).glob("*.mcap")):
        row = {"file": p.name, "size_bytes": p.stat().st_size, "start": "", "duration_s": None,
               "robots": None, "state": ""}
        try:
            with open_recording(p) as rec:
                first = rec.first_frame
                created = rec.metadata.get("created", "")
                row["start"] = created
                row["duration_s"] = rec.duration
                row["robots"] = None if first is None else first.n
                row["state"] = ("empty" if first is None else "damaged" if rec.damaged
                                else "ok" if rec.indexed else "recovered")
        except RecordingError as exc:
            row["state"] = f"unreadable: {exc}"
        rows.append(row)
    rows.sort(key=lambda r: str(r["start"] or ""), reverse=True)
    return rows


def _when(iso: str) -> str:
    try:
        return dt.datetime.fromisoformat(iso).strftime("%Y-%m-%d %H:%M:%S UTC")
    except (TypeError, ValueError):
        return iso or "?"


def main(args: argparse.Namespace) -> int:
    d = Path(args.dir)
    if not d.is_dir():
        raise UsageError(f"{d} is not a folder (recordings go to sessions/ by default)")
    rows = list_sessions(d)
    if not rows:
        print(f"no recordings (*.mcap) in {d}")
        return 0
    print(f"{'file':<28} {'start':<24} {'duration':>10} {'robots':>6} {'size':>10}  state")
    for r in rows:
        dur = "" if r["duration_s"] is None else f"{r['duration_s']:.1f} s"
        rob = "" if r["robots"] is None else str(r["robots"])
        print(f"{r['file']:<28} {_when(r['start']):<24} {dur:>10} {rob:>6} {r['size_bytes'] / 1e6:>8.2f} MB  {r['state']}")
    return 0
