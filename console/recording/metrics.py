"""The metrics of one recorded run, and what differs between runs (``swarmdeck compare``, issue 31 item 4).

:func:`run_metrics` reads every readable frame of a recording once (a damaged file: the readable part, its
warnings kept) and returns a :class:`RunMetrics`:

* ``duration_s`` (first to last frame, s), ``frames``, ``robots`` (N of the first frame; the largest N when it
  changes), ``bounds`` (x_min, x_max, y_min, y_max, m), ``dt`` (s), ``behaviours``;
* ``contacts``: contact onsets — a pair of robots whose centres come closer than the robot diameter
  (:data:`~swarmdeck.core.constants.ROBOT_DIAMETER`, bodies touch; REFERENCE.md §4) in a frame where they were
  not in the frame before; ``contact_frames``: frames with at least one pair in contact;
* ``min_distance_m``: the smallest centre-to-centre distance of two robots over the run (m; None below two
  robots);
* ``interventions``: robot-ticks whose command the barrier changed (by more than the picture's
  ``changed_threshold``: :func:`~swarmdeck.console.picture.picture.changed_mask`, the robots drawn orange);
  ``intervention_frames``: frames with at least one; ``filter_failures``: frames whose filter did not certify;
* ``coverage_cost_final`` / ``coverage_cost_mean``: the coverage cost H of the last frame with a coverage state
  and its mean over those frames (None when no frame has one);
* ``distance_m``: the distance all robots travelled (sum over robots of the path length of the robot centres,
  m; a jump in the tick index or a change of robots starts a new path); ``distance_per_robot_m`` its mean;
* ``stopped_frames`` (emergency stop), ``events``, ``warnings`` (damage; the metrics are of the readable part).

Per frame the work is vectorised over robots: a k-d tree for the nearest neighbours and the pairs in contact
(no N×N matrix).
"""
from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmdeck.console.picture.picture import changed_mask
from swarmdeck.console.recording.reader import Recording
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.core.constants import ROBOT_DIAMETER

METRICS: tuple[tuple[str, str], ...] = (
    ("duration_s", "duration (s)"),
    ("frames", "frames"),
    ("robots", "robots"),
    ("arena", "arena (m)"),
    ("dt", "control period (s)"),
    ("behaviours", "behaviours"),
    ("contacts", "contacts (onsets)"),
    ("contact_frames", "frames with a contact"),
    ("min_distance_m", "minimum distance (m, centres)"),
    ("interventions", "barrier interventions (robot-ticks)"),
    ("intervention_frames", "frames with an intervention"),
    ("filter_failures", "filter failures (frames)"),
    ("coverage_cost_final", "coverage cost H (last)"),
    ("coverage_cost_mean", "coverage cost H (mean)"),
    ("distance_m", "distance travelled (m, all robots)"),
    ("distance_per_robot_m", "distance per robot (m)"),
    ("stopped_frames", "emergency-stopped frames"),
    ("events", "events"),
)
"""The rows of the comparison table: (key of :meth:`RunMetrics.row`, label)."""


@dataclass(frozen=True)
class RunMetrics:
    """The metrics of one recording (see the module docstring for each field and its unit)."""

    file: str
    duration_s: float
    frames: int
    robots: int
    bounds: tuple[float, float, float, float]
    dt: float
    behaviours: tuple[str, ...]
    contacts: int
    contact_frames: int
    min_distance_m: float | None
    interventions: int
    intervention_frames: int
    filter_failures: int
    coverage_cost_final: float | None
    coverage_cost_mean: float | None
    distance_m: float
    distance_per_robot_m: float
    stopped_frames: int
    events: int
    warnings: tuple[str, ...] = ()

    @property
    def arena(self) -> str:
        """The arena as "W × H at (x_min, y_min)", m."""
        return arena_text(self.bounds)

    def setup(self) -> dict[str, str]:
        """What makes runs like for like (:func:`differences`): arena, robots, control period, behaviours."""
        return {"arena (m)": self.arena, "robots": str(self.robots), "control period (s)": f"{self.dt:.4g}",
                "behaviours": ", ".join(self.behaviours)}

    def row(self) -> dict[str, Any]:
        """The table's values by key (:data:`METRICS`)."""
        d = asdict(self)
        d["arena"] = self.arena
        d["behaviours"] = ", ".join(self.behaviours)
        return d

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: every field (``bounds`` and tuples as lists; None where a metric is undefined)."""
        d = asdict(self)
        d["bounds"], d["behaviours"], d["warnings"] = list(self.bounds), list(self.behaviours), list(self.warnings)
        d["arena"] = self.arena
        return d


def _nearest(xy: NDArray[np.float64]) -> tuple[float, NDArray[np.int64]]:
    """(smallest centre distance m (inf below 2 robots), pairs closer than the robot diameter (K, 2) i < j)."""
    if len(xy) < 2:
        return math.inf, np.empty((0, 2), dtype=np.int64)
    from scipy.spatial import cKDTree  # lazy: see test_devices_rps_startup_imports

    tree = cKDTree(xy)
    d, _ = tree.query(xy, k=2)
    pairs = tree.query_pairs(ROBOT_DIAMETER, output_type="ndarray").astype(np.int64)
    return float(d[:, 1].min()), pairs


def _pair_keys(pairs: NDArray[np.int64], ids: NDArray[np.int64]) -> set[tuple[int, int]]:
    """The pairs as robot-id pairs (smaller id first), so onsets survive a reordering of the robots."""
    a, b = ids[pairs[:, 0]], ids[pairs[:, 1]]
    return set(zip(np.minimum(a, b).tolist(), np.maximum(a, b).tolist()))


def run_metrics(recording: Recording) -> RunMetrics:
    """The metrics of every readable frame of ``recording`` (ValueError when it holds none)."""
    first = recording.first_frame
    if first is None:
        raise ValueError(f"{recording.path} holds no readable frame")
    frames = contacts = contact_frames = interventions = intervention_frames = failures = stopped = 0
    robots = 0
    dmin = math.inf
    distance = 0.0
    h_sum, h_count, h_last = 0.0, 0, None
    behaviours: dict[str, None] = {}
    in_contact: set[tuple[int, int]] = set()
    prev_tick: int | None = None
    prev_ids: NDArray[np.int64] | None = None
    prev_xy: NDArray[np.float64] | None = None
    for _t, f in recording.frames():
        frames += 1
        robots = max(robots, f.n)
        behaviours.setdefault(f.behaviour, None)
        xy = f.poses[:, :2]
        d, pairs = _nearest(xy)
        dmin = min(dmin, d)
        now = _pair_keys(pairs, f.ids) if len(pairs) else set()
        contacts += len(now - in_contact)
        contact_frames += bool(now)
        in_contact = now
        changed = int(np.count_nonzero(changed_mask(f)))
        interventions += changed
        intervention_frames += changed > 0
        failures += f.barrier is not None and f.barrier.enabled and not f.barrier.ok
        stopped += f.run_state == "estop"
        if f.coverage is not None and math.isfinite(f.coverage.cost_H):
            h_last = float(f.coverage.cost_H)
            h_sum += h_last
            h_count += 1
        if (prev_xy is not None and prev_ids is not None and prev_tick is not None and f.tick == prev_tick + 1
                and np.array_equal(prev_ids, f.ids)):
            distance += float(np.linalg.norm(xy - prev_xy, axis=1).sum())
        prev_tick, prev_ids, prev_xy = f.tick, f.ids, xy
    n_events = sum(1 for _ in recording.events())
    return RunMetrics(
        file=str(recording.path), duration_s=recording.duration, frames=frames, robots=robots,
        bounds=tuple(float(b) for b in first.bounds), dt=first.dt,  # type: ignore[arg-type]
        behaviours=tuple(behaviours), contacts=contacts, contact_frames=contact_frames,
        min_distance_m=None if math.isinf(dmin) else dmin, interventions=interventions,
        intervention_frames=intervention_frames, filter_failures=failures,
        coverage_cost_final=h_last, coverage_cost_mean=h_sum / h_count if h_count else None,
        distance_m=distance, distance_per_robot_m=distance / robots if robots else 0.0,
        stopped_frames=stopped, events=n_events, warnings=tuple(recording.warnings),
    )


def arena_text(bounds: Sequence[float]) -> str:
    """An arena rectangle (x_min, x_max, y_min, y_max, m) as "W × H at (x_min, y_min)"."""
    x0, x1, y0, y1 = bounds
    return f"{x1 - x0:.3g} × {y1 - y0:.3g} at ({x0:.3g}, {y0:.3g})"


def frame_setup(frame: Frame) -> dict[str, str]:
    """What makes runs like for like, from one frame: the arena, the number of robots, the control period."""
    return {"arena (m)": arena_text(frame.bounds), "robots": str(frame.n), "control period (s)": f"{frame.dt:.4g}"}


def differences(setups: Sequence[Mapping[str, str]], names: Sequence[str] | None = None) -> list[str]:
    """What differs between runs (their :meth:`RunMetrics.setup` or :func:`frame_setup`), one line per item
    naming every run's value by its name (default its letter, A, B, …; [] when all agree)."""
    called = [run_letter(i) for i in range(len(setups))] if names is None else list(names)
    out: list[str] = []
    for label in dict.fromkeys(k for s in setups for k in s):
        values = [s.get(label, "–") for s in setups]
        if len(set(values)) > 1:
            out.append(f"{label} differ: " + "; ".join(f"{n} {v}" for n, v in zip(called, values)))
    return out


def run_names(runs: Sequence[RunMetrics]) -> list[str]:
    """Short names for the runs: A, B, C, … (then run27, …) — the letters the player's legend uses."""
    return [run_letter(i) for i in range(len(runs))]


def run_letter(i: int) -> str:
    """The name of run ``i`` (0-based): A … Z, then run27, run28, …"""
    return chr(ord("A") + i) if i < 26 else f"run{i + 1}"


def _cell(value: Any) -> str:
    if value is None:
        return "–"
    if isinstance(value, bool):
        return str(value)
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return f"{value:.4g}" if abs(value) < 1e4 else f"{value:.6g}"
    return str(value)


def table(runs: Sequence[RunMetrics]) -> str:
    """The comparison as a plain-text table: one row per metric (:data:`METRICS`), one column per run."""
    names = run_names(runs)
    header = ["metric"] + names
    rows = [[label] + [_cell(r.row()[key]) for r in runs] for key, label in METRICS]
    widths = [max(len(line[c]) for line in [header] + rows) for c in range(len(header))]
    fmt = "  ".join(f"{{:<{w}}}" if c == 0 else f"{{:>{w}}}" for c, w in enumerate(widths))
    lines = [fmt.format(*header), fmt.format(*("-" * w for w in widths))]
    lines += [fmt.format(*row) for row in rows]
    return "\n".join(lines)


def comparison(runs: Sequence[RunMetrics], names: Sequence[str] | None = None) -> dict[str, Any]:
    """The comparison as JSON (``swarmdeck compare --json``, the portal's job comparison): ``runs`` (each run's
    :meth:`RunMetrics.to_dict` with its ``name``), ``differences`` (:func:`differences`) and ``metrics`` (the
    table's rows: key and label, :data:`METRICS`)."""
    letters = [run_letter(i) for i in range(len(runs))] if names is None else list(names)
    return {
        "runs": [{"name": n, **r.to_dict()} for n, r in zip(letters, runs)],
        "differences": differences([r.setup() for r in runs], letters),
        "metrics": [{"key": k, "label": label} for k, label in METRICS],
    }
