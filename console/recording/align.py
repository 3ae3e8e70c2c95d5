"""Several recordings on one timeline (``swarmdeck play A.mcap B.mcap …``, issue 31 item 4).

Each run is aligned at an anchor, a time of its own recording (s since its first frame):

* ``start`` — its first frame (time 0; the default);
* ``t:SECONDS`` — that recording time, e.g. ``t:12.5``;
* ``event:NAME`` — the first recorded event whose text contains ``NAME`` (as ``swarmdeck info`` lists them),
  e.g. ``event:behaviour: goto``.

The anchors are put at the same timeline time: with anchors a_i, run i's recording time r at timeline time τ is
``r = τ − offset_i`` with ``offset_i = max_j a_j − a_i`` (so every offset is ≥ 0 and the timeline starts at 0
with the run whose anchor is latest). The timeline ends with the last run: ``max_i (offset_i + duration_i)``.
Before its offset a run shows its first frame, after its end its last (``Recording.frame_at`` clamps).
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

from swarmdeck.console.recording.reader import Recording

AnchorKind = Literal["start", "t", "event"]
ALIGN_HELP = "start | t:SECONDS | event:NAME"


@dataclass(frozen=True)
class Anchor:
    """Where a run is aligned: ``kind`` start / t (``seconds``, recording time) / event (``name``, a substring of
    the event's text)."""

    kind: AnchorKind = "start"
    seconds: float = 0.0
    name: str = ""

    def __str__(self) -> str:
        return {"start": "start", "t": f"t:{self.seconds:g}", "event": f"event:{self.name}"}[self.kind]


def parse_anchor(text: str) -> Anchor:
    """``start``, ``t:SECONDS`` or ``event:NAME`` → :class:`Anchor`; ValueError naming what is wrong."""
    s = text.strip()
    if s == "start":
        return Anchor()
    kind, sep, rest = s.partition(":")
    if sep and kind == "t":
        try:
            sec = float(rest)
        except ValueError:
            raise ValueError(f"--align {text!r}: t: needs a number of seconds, e.g. t:12.5") from None
        if not math.isfinite(sec) or sec < 0:
            raise ValueError(f"--align {text!r}: the time must be a finite number of seconds ≥ 0")
        return Anchor("t", seconds=sec)
    if sep and kind == "event":
        if not rest.strip():
            raise ValueError(f"--align {text!r}: event: needs (part of) an event's text, e.g. event:e-stop")
        return Anchor("event", name=rest)
    raise ValueError(f"--align {text!r}: expected {ALIGN_HELP}")


def anchors_for(texts: Sequence[str], n_runs: int) -> list[Anchor]:
    """The anchors of ``n_runs`` runs from the ``--align`` values given: none → every run at its start; one →
    the same anchor for every run; ``n_runs`` → one per run, in order. ValueError otherwise."""
    parsed = [parse_anchor(t) for t in texts]
    if not parsed:
        return [Anchor()] * n_runs
    if len(parsed) == 1:
        return parsed * n_runs
    if len(parsed) != n_runs:
        raise ValueError(f"--align given {len(parsed)} times for {n_runs} recordings: give it once (the same "
                         "anchor for all) or once per recording, in order")
    return parsed


def anchor_time(recording: Recording, anchor: Anchor) -> float:
    """The anchor's recording time in ``recording``, s. ValueError naming the file when a ``t:`` lies past its
    end or no event matches (the error lists a few of its events)."""
    if anchor.kind == "start":
        return 0.0
    if anchor.kind == "t":
        if anchor.seconds > recording.duration + 1e-9:
            raise ValueError(f"{recording.path.name}: --align t:{anchor.seconds:g} is past its end "
                             f"({recording.duration:.2f} s)")
        return anchor.seconds
    seen: list[str] = []
    for e in recording.events():
        if anchor.name in e.text:
            return e.t
        if len(seen) < 5:
            seen.append(f"{e.t:.2f} s {e.text}")
    listed = "; ".join(seen) if seen else "it has no events"
    raise ValueError(f"{recording.path.name}: no event contains {anchor.name!r} (first events: {listed})")


def offsets_for(anchor_times: Sequence[float]) -> tuple[float, ...]:
    """Timeline offsets (s) that put the anchors at one timeline time: ``max(a) − a_i`` (see the module)."""
    if not anchor_times:
        return ()
    top = max(anchor_times)
    return tuple(top - a for a in anchor_times)


def timeline_duration(offsets: Sequence[float], durations: Sequence[float]) -> float:
    """The timeline's length, s: ``max_i (offset_i + duration_i)``."""
    return max(o + d for o, d in zip(offsets, durations))


def align(recordings: Sequence[Recording], anchors: Sequence[Anchor]) -> tuple[float, ...]:
    """The offsets of ``recordings`` aligned at ``anchors`` (one each)."""
    if len(anchors) != len(recordings):
        raise ValueError(f"{len(anchors)} anchors for {len(recordings)} recordings")
    return offsets_for([anchor_time(r, a) for r, a in zip(recordings, anchors)])
