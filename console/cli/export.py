"""``swarmdeck export FILE --csv DIR --html OUT.html --video OUT.mp4``: a recording for other tools and people."""
from __future__ import annotations

import argparse
import re
import sys

from swarmdeck.console.cli import UsageError

NAME = "export"
HELP = ("export a recorded session: --csv DIR (poses and commands per robot), --html OUT.html (standalone 3D replay) "
        "and/or --video OUT.mp4 (top-down H.264 video)")
ORDER = 64

HTML_FPS, VIDEO_FPS = 10.0, 30.0


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("file", help="a .mcap recording")
    parser.add_argument("--csv", metavar="DIR", help="write DIR/robots.csv (one row per robot per frame) and DIR/frames.csv")
    parser.add_argument("--html", metavar="OUT.html", help="write a standalone HTML replay (viser scene serializer)")
    parser.add_argument("--video", metavar="OUT.mp4",
                        help="write an MP4 video (H.264) drawn from above: robots, Voronoi cells, density, barrier "
                             "activity, events, time, and the camera picture when a camera ran")
    parser.add_argument("--fps", type=float, default=None,
                        help=f"frames per second of recording time: HTML replay (default {HTML_FPS:g}) and video "
                             f"(default {VIDEO_FPS:g})")
    parser.add_argument("--size", default="1280x720", metavar="WxH", help="video size in pixels (default 1280x720)")
    parser.add_argument("--start", type=float, default=None, metavar="S", help="from S s after the first frame")
    parser.add_argument("--end", type=float, default=None, metavar="S", help="up to S s after the first frame")


def parse_size(text: str) -> tuple[int, int]:
    """``"1280x720"`` → (1280, 720); UsageError unless two even sizes in [64, 4096]."""
    m = re.fullmatch(r"\s*(\d+)\s*[xX×]\s*(\d+)\s*", text)
    if not m:
        raise UsageError(f"--size must look like 1280x720, got {text!r}")
    w, h = int(m.group(1)), int(m.group(2))
    for name, v in (("width", w), ("height", h)):
        if not (64 <= v <= 4096 and v % 2 == 0):
            raise UsageError(f"--size {name} must be an even number of pixels in [64, 4096], got {v}")
    return w, h


def main(args: argparse.Namespace) -> int:
    from swarmdeck.console.recording.export_csv import export_csv
    from swarmdeck.console.recording.reader import RecordingError, open_recording

    if not args.csv and not args.html and not args.video:
        raise UsageError("say what to export: --csv DIR, --html OUT.html and/or --video OUT.mp4")
    if args.fps is not None and not (0 < args.fps <= 120):
        raise UsageError(f"--fps must be in (0, 120], got {args.fps}")
    if args.start is not None and args.end is not None and not args.start < args.end:
        raise UsageError(f"--start ({args.start}) must be before --end ({args.end})")
    size = parse_size(args.size) if args.video else None
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
                path, n = export_html(rec, args.html, fps=args.fps or HTML_FPS, start=args.start, end=args.end)
            except OSError as exc:
                raise UsageError(f"cannot write {args.html}: {exc.strerror or exc}") from exc
            print(f"wrote a {n}-frame replay to {path} (open it in a browser)")
        if args.video:
            assert size is not None
            _video(rec, args.video, args.fps or VIDEO_FPS, size, args.start, args.end)
    return 0


def _video(rec, out: str, fps: float, size: tuple[int, int], start: float | None, end: float | None) -> None:
    from tqdm import tqdm

    from swarmdeck.console.recording.export_video import VideoExportError, VideoStyle, export_video

    bar = tqdm(total=0, unit="frame", desc=f"video {out}", file=sys.stderr, leave=False,
               disable=None)  # no bar when stderr is not a terminal

    def progress(done: int, total: int) -> None:
        if bar.total != total:
            bar.reset(total=total)
        bar.update(done - bar.n)

    try:
        path, n = export_video(rec, out, VideoStyle(width=size[0], height=size[1], fps=fps), start, end, progress)
    except VideoExportError as exc:
        raise UsageError(str(exc)) from exc
    except OSError as exc:
        raise UsageError(f"cannot write {out}: {exc.strerror or exc}") from exc
    finally:
        bar.close()
    print(f"wrote a {n}-frame video ({n / fps:.1f} s at {fps:g} fps, {size[0]}x{size[1]}, H.264) to {path}")
