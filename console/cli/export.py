"""``swarmdeck export FILE --csv DIR --html OUT.html``: a recording for other tools."""
from __future__ import annotations

import argparse

from swarmdeck.console.cli import UsageError

NAME = "export"
HELP = "export a recorded session: --csv DIR (poses and commands per robot) and/or --html OUT.html (standalone 3D replay)"
ORDER = 64


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("file", help="a .mcap recording")
    parser.add_argument("--csv", metavar="DIR", help="write DIR/robots.csv (one row per robot per frame) and DIR/frames.csv")
    parser.add_argument("--html", metavar="OUT.html", help="write a standalone HTML replay (viser scene serializer)")
    parser.add_argument("--fps", type=float, default=10.0, help="frames per second sampled into the HTML replay (default 10)")
    parser.add_argument("--start", type=float, default=None, metavar="S", help="from S s after the first frame")
    parser.add_argument("--end", type=float, default=None, metavar="S", help="up to S s after the first frame")


def main(args: argparse.Namespace) -> int:
    from swarmdeck.console.recording.export_csv import export_csv
    from swarmdeck.console.recording.reader import RecordingError, open_recording

    if not args.csv and not args.html:
        raise UsageError("say what to export: --csv DIR and/or --html OUT.html")
    if not (args.fps > 0):
        raise UsageError(f"--fps must be > 0, got {args.fps}")
    if args.start is not None and args.end is not None and not args.start < args.end:
        raise UsageError(f"--start ({args.start}) must be before --end ({args.end})")
    try:
        rec = open_recording(args.file)
    except RecordingError as exc:
        raise UsageError(str(exc)) from exc
    with rec:
        if rec.empty:
            raise UsageError(f"{args.file} holds no readable frame")
        for w in rec.warnings:
            print(f"warning: {w}")
        if args.csv:
            try:
                robots, frames, n = export_csv(rec, args.csv, args.start, args.end)
            except OSError as exc:
                raise UsageError(f"cannot write CSV to {args.csv}: {exc.strerror or exc}") from exc
            print(f"wrote {n} frames to {robots} and {frames}")
        if args.html:
            from swarmdeck.console.recording.export_html import export_html

            try:
                path, n = export_html(rec, args.html, fps=args.fps, start=args.start, end=args.end)
            except OSError as exc:
                raise UsageError(f"cannot write {args.html}: {exc.strerror or exc}") from exc
            print(f"wrote a {n}-frame replay to {path} (open it in a browser)")
    return 0
