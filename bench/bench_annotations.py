"""Benchmark of what experiments draw (issue 29 item 3): annotation throughput per tick, before the cap.

    .venv/bin/python bench/bench_annotations.py

For P primitives drawn per tick (P = 10, 100, 1000 and the cap, 4096; and a million, over the cap) the
stages one tick's drawing goes through, CPU time per tick (median over repeats; the VM is shared):

* draw — the script's calls: one vectorised ``arena.draw.points(xy)`` (rows ``points``), or P separate
  ``arena.draw.circle(...)`` calls (at most 4096: the cap; the Python cost per call);
* collect — ``Annotator.collect``: the tick's live set, expired ones dropped, checked and capped
  (``sanitize``: NaN refused, clipped into the arena, the caps);
* record — the codec's ``annotations_message`` + decode of the frame's annotations (what the recorder writes);
* pipe — the sandbox's ``draw`` message: encode + ``decode_draw`` on the trusted side;
* live JSON — ``annotations_json`` (the portal's live view, the projector page);
* video — ``draw_annotations`` onto a 1280 × 720 image; Foxglove — the ``/foxglove/annotations`` SceneUpdate.

The last column says how many primitives per tick fit in one 33 ms control period for the whole chain
drawn from one vectorised call (draw + collect + record), a ratio to the cap.
"""
from __future__ import annotations

import time

import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads
import numpy as np

from swarmdeck.console.picture.annotations import annotations_json
from swarmdeck.console.recording.codec import annotations_message, decode_annotations
from swarmdeck.console.recording.export_video import VideoLayout
from swarmdeck.console.recording.foxglove import FoxgloveEncoder
from swarmdeck.console.recording.video_annotations import draw_annotations
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.console.sandbox.protocol import decode_draw, encode_annotations
from swarmdeck.core.annotator import Annotator
from swarmdeck.core.bounds import DEFAULT_BOUNDS
from swarmdeck.core.constants import CONTROL_PERIOD

SIZES = (10, 100, 1000, 4096, 1_000_000)
REPEATS = 7


def frame_with(ann) -> Frame:
    return Frame(tick=0, time=0.0, poses=np.zeros((1, 3)), ids=[0], nominal=np.zeros((1, 2)), safe=np.zeros((1, 2)),
                 v=[0.0], w=[0.0], annotations=ann)


def row(p: int, xy: np.ndarray, layout: VideoLayout, image: np.ndarray, fox: FoxgloveEncoder) -> str:
    """The table row of ``p`` primitives per tick at ``xy`` (p, 2) m."""
    cpu = "cpu"

    def draw_points() -> Annotator:
        a = Annotator()
        a.points(xy, radius=0.01, color="red")
        return a

    t_points = harness.measure(draw_points, REPEATS, clock=cpu).median
    n_calls = min(p, 4096)

    def draw_circles() -> None:
        a = Annotator()
        for x, y in xy[:n_calls]:
            a.circle((x, y), 0.02, color="blue")

    t_circles = harness.measure(draw_circles, 3, clock=cpu).median
    ann = draw_points().collect(0.0)
    t_collect = harness.measure(lambda: draw_points().collect(0.0), REPEATS, clock=cpu).median - t_points
    frame = frame_with(ann)
    t_record = harness.measure(lambda: decode_annotations(annotations_message(frame)["annotations"]),
                               REPEATS, clock=cpu).median
    t_pipe = harness.measure(lambda: decode_draw(encode_annotations(ann)), REPEATS, clock=cpu).median
    t_json = harness.measure(lambda: annotations_json(ann), REPEATS, clock=cpu).median
    t_video = harness.measure(lambda: draw_annotations(image.copy(), ann, layout.to_px, layout.scale), 3,
                              clock=cpu).median
    t_fox = harness.measure(lambda: fox.annotations(frame, 0), 3, clock=cpu).median
    return harness.table_row(f"{p:,}", f"{t_points * 1e3:.2f}", f"{t_circles * 1e3:.1f}",
                             f"{max(t_collect, 0.0) * 1e3:.2f}", f"{t_record * 1e3:.2f}", f"{t_pipe * 1e3:.2f}",
                             f"{t_json * 1e3:.2f}", f"{t_video * 1e3:.1f}", f"{t_fox * 1e3:.1f}", f"{len(ann):,}")


def main() -> int:
    rng = np.random.default_rng(0)
    base = harness.baseline()
    print(f"annotations benchmark — {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, {harness.machine()}")
    print(f"baseline (numpy sort 10⁵ ×10): {base.median * 1e3:.1f} ms")
    print()
    print(harness.table_header(["P per tick", "draw: points (ms)", "draw: circles, one call each, ≤ 4096 calls (ms)",
                                "collect (ms)", "record (ms)", "pipe (ms)", "live JSON (ms)", "video (ms)",
                                "Foxglove (ms)", "kept"], [True] * 10))
    layout = VideoLayout.fit(DEFAULT_BOUNDS, 1280, 720)
    image = np.full((720, 1280, 3), 250, dtype=np.uint8)
    fox = FoxgloveEncoder()
    for p in SIZES:
        print(row(p, rng.uniform(-1.5, 1.5, (p, 2)) * [1.0, 0.6], layout, image, fox))
    # what fits in one control period: the chain at the cap, scaled
    xy = rng.uniform(-1.5, 1.5, (4096, 2))

    def chain() -> None:
        a = Annotator()
        a.points(xy, radius=0.01)
        annotations_message(frame_with(a.collect(0.0)))

    t = harness.measure(chain, REPEATS, clock="cpu").median
    print()
    print(f"draw + collect + record at the cap (4096 points, one call): {t * 1e3:.2f} ms CPU per tick "
          f"= {4096 * CONTROL_PERIOD / t:,.0f} primitives per {CONTROL_PERIOD * 1e3:.0f} ms tick "
          f"({CONTROL_PERIOD / t:.1f}× the cap)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
