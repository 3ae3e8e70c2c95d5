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

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from swarmdeck.console.portal.errors import NotFound
from swarmdeck.console.recording.metrics import comparison, run_metrics
from swarmdeck.console.recording.reader import Recording, RecordingError, open_recording
from swarmdeck.console.recording.tracks import sampled_poses


def compare_recordings(paths: Sequence[Path], names: Sequence[str]) -> dict[str, Any]:
    """``{runs, differences, metrics, tracks: [{name, period, t, ids, bounds, poses}]}`` of the recordings
    (:func:`~swarmdeck.console.recording.metrics.comparison`); NotFound naming the run whose recording cannot
    be played."""
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
        result = comparison([run_metrics(r) for r in opened], names)
        for run in result["runs"]:
            run["file"] = Path(run["file"]).name  # not the lab's folder layout
        result["tracks"] = [{"name": n, **sampled_poses(r).to_dict()} for n, r in zip(names, opened)]
        return result
    finally:
        for r in opened:
            r.close()
