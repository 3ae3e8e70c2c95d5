"""``swarmdeck play FILE [FILE …]``: replay a recorded session in the browser, or several on one timeline."""
from __future__ import annotations

import argparse
import os
import sys
import threading
from collections.abc import Sequence
from typing import TYPE_CHECKING, TextIO

from swarmdeck.console.cli import UsageError

if TYPE_CHECKING:
    from swarmdeck.console.recording.reader import Recording
    from swarmdeck.console.web.player import PlayerApp

NAME = "play"
HELP = ("replay a recorded session in the browser: the console's scene with a timeline (seek, play, step, rate, "
        "loop, A/B); several recordings play on one timeline (overlaid or side by side)")
ORDER = 60


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("file", nargs="+",
                        help="a .mcap recording (see `swarmdeck sessions`); give several to play them on one "
                             "timeline: the first drawn solid, the others as ghosts in a colour each (or beside it)")
    parser.add_argument("--host", default="127.0.0.1", help="interface to listen on (default 127.0.0.1)")
    parser.add_argument("--port", type=int, default=8080, help="port (default 8080; 0 = any free port)")
    parser.add_argument("--start", type=float, default=0.0, metavar="S",
                        help="start at session time S s (s since the first frame: the times `swarmdeck info` "
                             "lists; with several recordings, timeline time)")
    parser.add_argument("--rate", type=float, default=1.0, help="playback rate 0.1–4 (default 1)")
    parser.add_argument("--loop", action="store_true", help="loop playback")
    parser.add_argument("--paused", action="store_true", help="open paused at --start")
    parser.add_argument("--align", action="append", default=[], metavar="ANCHOR",
                        help="several recordings: the moment put at the same timeline time — start (default), "
                             "t:SECONDS (that recording time) or event:NAME (the first event whose text contains "
                             "NAME, as `swarmdeck info` lists them); once for all, or once per recording in order")
    parser.add_argument("--layout", choices=("overlay", "side"), default="overlay",
                        help="several recordings: overlay (the others as translucent ghosts over the first; "
                             "default) or side (each in its own arena, in a row)")


def open_runs(paths: Sequence[str], warnings: TextIO | None = None) -> list[Recording]:
    """Open every recording for playing together; UsageError naming the file that cannot be played (not found,
    not a recording, no readable frame) or given twice. Damage warnings are printed (to ``warnings``, default
    stdout) with the file's name."""
    from swarmdeck.console.recording.reader import RecordingError, open_recording

    seen: dict[tuple[int, int], str] = {}
    for p in paths:
        try:
            st = os.stat(p)
        except OSError:
            continue  # open_recording names the problem
        key = (st.st_dev, st.st_ino)
        if key in seen:
            raise UsageError(f"{p} is given twice (it is {seen[key]}): give each recording once"
                             if seen[key] != p else f"{p} is given twice: give each recording once")
        seen[key] = p
    runs: list[Recording] = []
    try:
        for p in paths:
            try:
                rec = open_recording(p)
            except RecordingError as exc:
                raise UsageError(str(exc)) from exc
            runs.append(rec)
            if rec.empty:
                raise UsageError(f"{p} holds no readable frame" + (f" ({rec.warnings[0]})" if rec.warnings else ""))
            for w in rec.warnings:
                print(f"warning: {w}" if len(paths) == 1 else f"warning: {p}: {w}", file=warnings or sys.stdout)
    except UsageError:
        for r in runs:
            r.close()
        raise
    return runs


def open_player(args: argparse.Namespace) -> tuple[PlayerApp, list[Recording]]:
    """Everything ``play`` does before serving: check the options, open and align the recordings, make the
    player at ``--start`` with ``--rate``/``--loop`` (playing unless ``--paused``) and start its thread.
    UsageError for bad options or recordings (every file opened is closed again)."""
    from swarmdeck.console.recording.align import align, anchors_for
    from swarmdeck.console.web.player import RATE_MAX, RATE_MIN, PlayerApp

    if not RATE_MIN <= args.rate <= RATE_MAX:
        raise UsageError(f"--rate must be between {RATE_MIN} and {RATE_MAX}, got {args.rate}")
    if not 0 <= args.port <= 65535:
        raise UsageError(f"--port must be in 0..65535, got {args.port}")
    files = list(args.file)
    if len(files) == 1 and args.align:
        raise UsageError("--align lines up several recordings: give two or more")
    try:
        anchors = anchors_for(args.align, len(files))
    except ValueError as exc:
        raise UsageError(str(exc)) from exc
    runs = open_runs(files)
    try:
        offsets = align(runs, anchors) if len(runs) > 1 else None
        if len(runs) > 1:
            _say_differences(runs)
        app = PlayerApp(runs if len(runs) > 1 else runs[0], host=args.host, port=args.port, offsets=offsets,
                        layout=args.layout)
    except ValueError as exc:
        for r in runs:
            r.close()
        raise UsageError(str(exc)) from exc
    except OSError as exc:
        for r in runs:
            r.close()
        raise UsageError(f"cannot listen on {args.host}:{args.port}: {exc.strerror or exc}") from exc
    p = app.player
    p.set_rate(args.rate)
    p.set_loop(args.loop)
    app.rate.value = f"{args.rate:g}x" if args.rate in (0.1, 0.25, 0.5, 1.0, 2.0, 4.0) else app.rate.value
    app.loop.value = args.loop
    p.seek(args.start)
    app.refresh()  # the frame at --start (paused, the playback thread draws nothing until something changes)
    if not args.paused:
        p.play()
    app.start()
    return app, runs


def main(args: argparse.Namespace) -> int:
    app, runs = open_player(args)
    p = app.player
    if len(runs) == 1:
        print(f"playing {runs[0].path} ({runs[0].duration:.1f} s, {p.frame.n} robots) at http://{args.host}:{app.port} "
              "— Ctrl-C to quit")
    else:
        for name, rec, off in zip(app.names, runs, p.offsets):
            print(f"{name}: {rec.path} ({rec.duration:.1f} s, starts at {off:.2f} s on the timeline)")
        print(f"playing {len(runs)} recordings ({args.layout}, {p.duration:.1f} s timeline) at "
              f"http://{args.host}:{app.port} — Ctrl-C to quit")
    try:
        threading.Event().wait()
    finally:
        app.close()
        for r in runs:
            r.close()
    return 0


def _say_differences(runs: Sequence[Recording]) -> None:
    """Print what makes the runs not like for like (arena, robots, control period), from their first frames."""
    from swarmdeck.console.recording.metrics import differences, frame_setup

    for line in differences([frame_setup(r.first_frame) for r in runs if r.first_frame is not None]):
        print(f"note: the recordings' {line}")
