"""Two of a researcher's jobs compared (issue 31 item 4): the metric table and both runs' tracks for the job
page's overlaid view.

:func:`compare_recordings` opens each job's ``recording.mcap`` (a damaged one: its readable part, as ``swarmdeck
play`` does; one that cannot be played: 404 naming the job), computes the metrics of
:mod:`~swarmdeck.console.recording.metrics` and samples the robots' poses
(:mod:`~swarmdeck.console.recording.tracks`). Who may compare what is the service's rule
(:meth:`~swarmdeck.console.portal.service.PortalService.compare`: both jobs must be visible to the user — a
researcher's own — so another researcher's job is 404, as everywhere).
"""
from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from swarmdeck.console.portal.errors import NotFound
from swarmdeck.console.recording.metrics import RunMetrics, comparison, run_metrics
from swarmdeck.console.recording.reader import Recording, RecordingError, open_recording
from swarmdeck.console.recording.tracks import Tracks, sampled_poses

CACHED_RUNS = 32  # recordings whose metrics and tracks the service keeps (an ended job's recording never changes)


class RunCache:
    """The metrics and tracks of the last :data:`CACHED_RUNS` recordings read, keyed by path, size and mtime
    (thread-safe): a researcher reloading a comparison page does not re-read two whole recordings each time."""

    def __init__(self, size: int = CACHED_RUNS) -> None:
        self._size = size
        self._lock = threading.Lock()
        self._runs: OrderedDict[tuple[str, int, int], tuple[RunMetrics, Tracks]] = OrderedDict()
        self.reads = 0  # recordings read (misses), for tests

    def get(self, path: Path, rec: Recording) -> tuple[RunMetrics, Tracks]:
        st = path.stat()
        key = (str(path), st.st_size, st.st_mtime_ns)
        with self._lock:
            hit = self._runs.get(key)
            if hit is not None:
                self._runs.move_to_end(key)
                return hit
        got = (run_metrics(rec), sampled_poses(rec))
        with self._lock:
            self.reads += 1
            self._runs[key] = got
            while len(self._runs) > self._size:
                self._runs.popitem(last=False)
        return got


def compare_recordings(paths: Sequence[Path], names: Sequence[str], cache: RunCache | None = None) -> dict[str, Any]:
    """``{runs, differences, metrics, tracks: [{name, period, t, ids, bounds, poses}]}`` of the recordings
    (:func:`~swarmdeck.console.recording.metrics.comparison`; each run's numbers from ``cache`` when it has
    them); NotFound naming the run whose recording cannot be played."""
    opened: list[Recording] = []
    try:
        for path, name in zip(paths, names):
            try:
                rec = open_recording(path)
            except RecordingError as exc:
                raise NotFound(f"{name}'s recording cannot be played: {exc}", "with") from None
            opened.append(rec)
            if rec.empty:
                raise NotFound(f"{name}'s recording holds no readable frame", "with")
        got = [(run_metrics(r), sampled_poses(r)) if cache is None else cache.get(p, r)
               for p, r in zip(paths, opened)]
        result = comparison([m for m, _ in got], names)
        for run in result["runs"]:
            run["file"] = Path(run["file"]).name  # not the lab's folder layout
        result["tracks"] = [{"name": n, **t.to_dict()} for n, (_, t) in zip(names, got)]
        return result
    finally:
        for r in opened:
            r.close()
