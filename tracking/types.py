"""Value types that cross the tracking boundary: camera frames and tracked poses.

Contract (issue 9): camera sources yield :class:`CameraFrame`; the tracker turns a
frame into :class:`TrackedPoses` ``(ids, poses, seen, stamps, status)``. Extra fields here have
defaults so the contract's positional form keeps working.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True, eq=False)
class CameraFrame:
    """One camera image.

    image: (H, W, 3) uint8 RGB. stamp: capture time in seconds on the clock of the loop that
    reads the source (``time.monotonic()`` for real cameras, the virtual clock for the
    synthetic camera). index: frame counter of the source (increasing). wall:
    ``time.monotonic()`` when the image was captured/rendered/decoded (for latency figures).
    """

    image: np.ndarray
    stamp: float
    index: int = 0
    wall: float = float("nan")


@dataclass(frozen=True, eq=False)
class TrackedPoses:
    """Robot poses from the overhead camera, one row per robot id ever seen (or expected).

    ids: (N,) int robot ids (ArUco marker id = robot id), ascending.
    poses: (N, 3) ``[x, y, θ]`` in arena metres / radians; the last observed pose, NaN for an
        expected robot never seen.
    seen: (N,) bool, True when the robot was observed in the frame these poses come from.
    stamps: (N,) float, capture time of the last observation (``-inf`` when never seen).
    status: one human-readable line (homography state, stale and duplicate ids, errors).
    frame_stamp: capture time of the frame processed last (NaN when there was none).
    stale: (N,) bool, last observation older than the tracker's ``stale_after_s`` at the time
        of the read; stale robots must get zero commands.
    duplicate_ids: ids that appeared more than once in the frame (their pose was not updated).
    homography: "ok", "held" (new fit rejected, last good one used), "fallback" (configured
        homography) or "none" (no poses can be computed).
    """

    ids: np.ndarray
    poses: np.ndarray
    seen: np.ndarray
    stamps: np.ndarray
    status: str
    frame_stamp: float = float("nan")
    stale: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    duplicate_ids: tuple[int, ...] = ()
    homography: str = "none"

    def fresh(self, now: float, max_age: float) -> np.ndarray:
        """(N,) bool: last observation at most ``max_age`` seconds before ``now``."""
        return (now - self.stamps) <= max_age

    def pose_of(self, robot_id: int) -> np.ndarray | None:
        """The (3,) pose of one robot, or None when it is not listed."""
        k = np.flatnonzero(self.ids == robot_id)
        return None if k.size == 0 else self.poses[k[0]].copy()

    @staticmethod
    def empty(status: str) -> TrackedPoses:
        """No robots at all, with a status line."""
        return TrackedPoses(
            ids=np.zeros(0, dtype=int), poses=np.zeros((0, 3)), seen=np.zeros(0, dtype=bool),
            stamps=np.zeros(0), status=status)

    def to_dict(self) -> dict:
        """JSON-able form (NaN/inf become None)."""
        def clean(a: np.ndarray) -> list:
            return [None if not np.isfinite(v) else float(v) for v in np.ravel(a)]
        return {
            "ids": [int(i) for i in self.ids],
            "poses": [clean(p) for p in self.poses],
            "seen": [bool(s) for s in self.seen],
            "stamps": clean(self.stamps),
            "stale": [bool(s) for s in self.stale],
            "status": self.status,
            "frame_stamp": clean(np.array([self.frame_stamp]))[0],
            "duplicate_ids": list(self.duplicate_ids),
            "homography": self.homography,
        }
