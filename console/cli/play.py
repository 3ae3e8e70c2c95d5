"""``swarmdeck play FILE``: replay a recorded session in the browser."""
from __future__ import annotations

import argparse
import threading

from swarmdeck.console.cli import UsageError

NAME = "play"
HELP = "replay a recorded session in the browser: the console's scene with a timeline (seek, play, step, rate, loop, A/B)"
ORDER = 60


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("file", help="a .mcap recording (see `swarmdeck sessions`)")
    parser.add_argument("--host", default="127.0.0.1", help="interface to listen on (default 127.0.0.1)")
    parser.add_argument("--port", type=int, default=8080, help="port (default 8080; 0 = any free port)")
    parser.add_argument("--start", type=float, default=0.0, metavar="S", help="start at session time S s (s since the first frame: the times `swarmdeck info` lists)")
    parser.add_argument("--rate", type=float, default=1.0, help="playback rate 0.1–4 (default 1)")
    parser.add_argument("--loop", action="store_true", help="loop playback")
    parser.add_argument("--paused", action="store_true", help="open paused at --start")


def main(args: argparse.Namespace) -> int:
    from swarmdeck.console.recording.reader import RecordingError, open_recording
    from swarmdeck.console.web.player import RATE_MAX, RATE_MIN, PlayerApp

    if not RATE_MIN <= args.rate <= RATE_MAX:
        raise UsageError(f"--rate must be between {RATE_MIN} and {RATE_MAX}, got {args.rate}")
    if not 0 <= args.port <= 65535:
        raise UsageError(f"--port must be in 0..65535, got {args.port}")
    try:
        rec = open_recording(args.file)
    except RecordingError as exc:
        raise UsageError(str(exc)) from exc
    if rec.empty:
        rec.close()
        raise UsageError(f"{args.file} holds no readable frame" + (f" ({rec.warnings[0]})" if rec.warnings else ""))
    for w in rec.warnings:
        print(f"warning: {w}")
    try:
        app = PlayerApp(rec, host=args.host, port=args.port)
    except OSError as exc:
        rec.close()
        raise UsageError(f"cannot listen on {args.host}:{args.port}: {exc.strerror or exc}") from exc
    p = app.player
    p.set_rate(args.rate)
    p.set_loop(args.loop)
    app.rate.value = f"{args.rate:g}x" if args.rate in (0.1, 0.25, 0.5, 1.0, 2.0, 4.0) else app.rate.value
    app.loop.value = args.loop
    p.seek(args.start)
    if not args.paused:
        p.play()
    app.start()
    print(f"playing {rec.path} ({rec.duration:.1f} s, {p.frame.n} robots) at http://{args.host}:{app.port} "
          "— Ctrl-C to quit")
    try:
        threading.Event().wait()
    finally:
        app.close()
        rec.close()
    return 0
