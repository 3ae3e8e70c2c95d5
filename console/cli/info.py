"""``swarmdeck info FILE``: summarise one recording."""
from __future__ import annotations

import argparse
import json
import os
from typing import Any

from swarmdeck.console.cli import UsageError

NAME = "info"
HELP = ("summarise a recorded session (start, duration, robots, channels, damage); event times are "
        "session time, s since the first frame, as `play --start` and the player's timeline take them")
ORDER = 62
BEHAVIOUR_EVENT = "behaviour: "  # the event the console posts on every behaviour change


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("file", help="a .mcap recording")
    parser.add_argument("--json", action="store_true", help="print the summary as JSON")
    parser.add_argument("--resimulate", action="store_true",
                        help="also re-run the session on a fresh simulated loop from its recorded input datagrams "
                             "and operator actions (run/pause/step/e-stop, behaviour, parameters, density bumps; "
                             "recordings from before those were recorded: reconstructed from the frames) and compare "
                             "every frame (exit code 1 when they differ)")


def summarise(path: str) -> dict:
    """The summary printed by ``swarmdeck info`` as a dict (RecordingError for unplayable files)."""
    from swarmdeck.console.recording.reader import open_recording
    from swarmdeck.console.recording.schemas import TOPIC_DATAGRAM, TOPIC_EVENT, TOPIC_OPERATOR

    with open_recording(path) as rec:
        cfg = rec.config()
        first = rec.first_frame
        counts = rec.message_counts()
        events: list[str] = []
        changes: list[dict[str, Any]] = []
        if first is not None:
            changes.append({"t": 0.0, "behaviour": first.behaviour})
        for e in rec.events():
            if len(events) < 10:
                events.append(f"{e.t:.3f} s [{e.kind}] {e.text}")  # session time: `play --start` seeks there
            if e.text.startswith(BEHAVIOUR_EVENT):  # every change the loop posted (ControlLoop.use_behaviour)
                name = e.text[len(BEHAVIOUR_EVENT):].strip()
                if not changes or changes[-1]["behaviour"] != name:
                    changes.append({"t": round(e.t, 3), "behaviour": name})
        n_datagrams = counts.get(TOPIC_DATAGRAM, 0)
        return {
            "file": str(rec.path),
            "size_bytes": os.path.getsize(rec.path),
            "created": cfg.get("created", rec.metadata.get("created")),
            "duration_s": rec.duration,
            "frames": rec.count_frames(),
            "datagrams": n_datagrams,
            "events": counts.get(TOPIC_EVENT, 0),
            # None: a recording from before operator actions were recorded (re-simulation reads its frames)
            "operator_actions": counts.get(TOPIC_OPERATOR, 0) if (cfg.get("config") or {}).get("operator_events")
            else None,
            "robots": list(cfg.get("robots", [] if first is None else first.ids.tolist())),
            "bounds": list(cfg.get("bounds", [] if first is None else first.bounds)),
            "dt": None if first is None else first.dt,
            "behaviours": list(dict.fromkeys(c["behaviour"] for c in changes)),
            "behaviour_changes": changes,
            "recording_format": rec.metadata.get("recording_format"),
            "frame_format": rec.metadata.get("frame_format"),
            "writer": rec.library,
            "versions": cfg.get("versions", rec.metadata.get("versions", {})),
            "config": cfg.get("config", {}),
            "chunks": rec.n_chunks,
            "closed_cleanly": rec.indexed,
            "warnings": list(rec.warnings),
            "first_events": events,
            "capsule": _capsule(path),
        }


def _capsule(path: str) -> dict[str, Any] | None:
    """What reproduces the recording (``swarmdeck capsule``): kind, files with SHA-256, run key; None without one,
    ``{"error": ...}`` for a capsule that does not match its files."""
    from swarmdeck.console.recording.capsule_zip import CapsuleError, read_recorded_capsule

    try:
        m = read_recorded_capsule(path).manifest
    except CapsuleError as exc:
        return {"error": str(exc)}
    return None if m is None else {"kind": m.kind, "files": m.files, "entry": m.entry, "key": m.key,
                                   "swarmdeck": m.swarmdeck}


def main(args: argparse.Namespace) -> int:
    from swarmdeck.console.recording.reader import RecordingError

    try:
        s = summarise(args.file)
    except RecordingError as exc:
        raise UsageError(str(exc)) from exc
    result = _resimulate(args.file) if args.resimulate else None
    if args.json:
        if result is not None:
            s["resimulation"] = {"frames": result.frames, "identical": result.identical, "ok": result.ok,
                                 "summary": result.summary(), "differing_keys": result.differing_keys}
        print(json.dumps(s, indent=2))
        return 0 if result is None or result.ok else 1
    robots = s["robots"]
    print(f"{s['file']}")
    print(f"  created     {s['created']}")
    print(f"  duration    {s['duration_s']:.2f} s, {s['frames']} frames (dt {s['dt']} s), "
          f"{s['datagrams']} input datagrams, {s['events']} events")
    print(f"  robots      {len(robots)}: {', '.join(map(str, robots[:30]))}{' …' if len(robots) > 30 else ''}")
    print(f"  arena       {s['bounds']} m")
    ops = s["operator_actions"]
    print("  operator    " + ("actions not recorded (reconstructed from the frames by --resimulate)" if ops is None
                              else f"{ops} recorded actions (replayed by --resimulate)"))
    print("  behaviour   " + ", then ".join(f"{c['behaviour']} (from {c['t']:.2f} s)" if c["t"] else c["behaviour"]
                                          for c in s["behaviour_changes"]))
    print(f"  size        {s['size_bytes'] / 1e6:.2f} MB in {s['chunks']} chunks"
          f"{'' if s['closed_cleanly'] else ' (not closed cleanly: recovered by scanning)'}")
    print(f"  format      recording {s['recording_format']}, frame {s['frame_format']}, written by {s['writer']}")
    cap = s["capsule"]
    if cap is not None:
        print("  capsule     " + (cap["error"].splitlines()[0] if "error" in cap else
                                  f"{cap['kind']}: {len(cap['files'])} script file(s), key {cap['key'][:16]}… "
                                  f"(swarmdeck capsule {s['file']} -o run.zip)"))
    for w in s["warnings"]:
        print(f"  warning     {w}")
    if s["first_events"]:
        print("  events      (t = session time, s since the first frame: `swarmdeck play FILE --start t`)")
    for e in s["first_events"]:
        print(f"  event       {e}")
    if result is not None:
        print(result.summary())
        return 0 if result.ok else 1
    return 0


def _resimulate(path: str):
    from swarmdeck.console.recording.reader import open_recording
    from swarmdeck.console.recording.resimulate import resimulate_and_compare

    with open_recording(path) as rec:
        try:
            return resimulate_and_compare(rec)
        except ValueError as exc:
            raise UsageError(f"cannot re-simulate {path}: {exc}") from exc
