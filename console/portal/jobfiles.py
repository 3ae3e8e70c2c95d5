"""A job's folder: its layout, the submission stored in it, its results and reports, and the video made on demand.

``DIR/jobs/<id>/`` holds, under names the portal chooses (a download names one of :data:`RESULT_FILES`, never a
path):

* the submission: ``script.py``, or ``src/<checked member names>`` for a ``.zip``; ``manifest.json``;
* verification: ``report.json``, ``report.html``, ``worst-case.mcap`` (the falsifier's worst case) (:mod:`.workers`);
* the arena run: ``recording.mcap`` (``recording.partial.mcap`` after a recovery), ``script.log``, ``run.json``
  (:mod:`.runner`), and the exports ``robots.csv``, ``frames.csv``, ``replay.html``, ``video.mp4``,
  ``capsule.zip`` (:mod:`.exports`).

Folders are ``0700`` and files ``0600`` (:mod:`.files`). The rules — who may read which job, whether its results
still exist — are the service's (:mod:`.service`); this module only knows files.
"""
from __future__ import annotations

import json
import shutil
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from swarmdeck.console.portal.errors import NotFound, Unavailable
from swarmdeck.console.portal.exports import EXPORT_FILES
from swarmdeck.console.portal.files import private_dir, write_private
from swarmdeck.console.portal.job import ExportState, Job
from swarmdeck.console.portal.states import FINAL
from swarmdeck.console.portal.submission import Manifest, Upload
from swarmdeck.console.sandbox.bundle import ScriptBundle

#: result files a job may have, name -> what it is (the exports, :mod:`.exports`, write four of them after the run).
RESULT_FILES: dict[str, str] = {
    "recording.mcap": "the run's MCAP recording (swarmdeck play / Foxglove)",
    "recording.partial.mcap": "the recording as the interrupted run left it (before recovery)",
    "robots.csv": "poses and commands per robot per frame (CSV)",
    "frames.csv": "one row per frame (CSV)",
    "replay.html": "standalone 3D replay (open in a browser)",
    "video.mp4": "top-down video of the run",
    "script.log": "the script's output (stdout and stderr)",
    "report.json": "the verification report (JSON)",
    "report.html": "the verification report (HTML)",
    "worst-case.mcap": "the worst case the verification's falsifier found, no barrier (MCAP: swarmdeck play)",
    "run.json": "how the run ended (JSON)",
    "manifest.json": "the manifest as accepted",
    "capsule.zip": "what reproduces the run: script files with SHA-256, settings, versions and the recording "
                   "(swarmdeck run capsule.zip re-executes it and says whether it is bit-identical)",
}
VIDEO = "video.mp4"
RECORDING = "recording.mcap"
WORST_CASE = "worst-case.mcap"


@dataclass(frozen=True)
class ResultFile:
    """One result file of a job: its name (a key of :data:`RESULT_FILES`), size in bytes (None: not made yet,
    the video made on its first download) and what it is."""

    name: str
    bytes: int | None
    what: str

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "bytes": self.bytes, "what": self.what}


class JobFiles:
    """The job folders under ``root`` (``DIR/jobs``); see the module docstring."""

    def __init__(self, root: Path) -> None:
        self.root = private_dir(Path(root))
        self._video_lock = threading.Lock()  # videos are made one at a time (video())

    def folder(self, job_id: int) -> Path:
        return self.root / str(int(job_id))

    # ------------------------------------------------------------------ the submission
    def store(self, job_id: int, upload: Upload, manifest: Manifest, entry: str) -> None:
        """Write the checked submission into the job's (new) folder: the script or the archive's members, and
        the manifest as accepted. A leftover folder of a rolled-back submission with this id is replaced."""
        folder = self.folder(job_id)
        if folder.exists():
            shutil.rmtree(folder)
        private_dir(folder)
        if upload.kind == "py":
            write_private(folder / "script.py", upload.files["script.py"])
        else:
            ScriptBundle.from_files(upload.files, entry).write_to(private_dir(folder / "src"), file_mode=0o600,
                                                                  dir_mode=0o700)
        write_private(folder / "manifest.json", json.dumps(manifest.to_dict(), indent=2))

    def script(self, job: Job) -> tuple[Path, str | None]:
        """What the sandbox runs for ``job``: ``(script.py, None)``, or ``(the archive's folder, its entry)``."""
        folder = self.folder(job.id)
        return (folder / "script.py", None) if job.kind == "py" else (folder / "src", job.entry)

    # ------------------------------------------------------------------ results
    def report(self, job_id: int) -> dict[str, Any] | None:
        """The verification report (``report.json``), None until verification has written it."""
        path = self.folder(job_id) / "report.json"
        if not path.is_file():
            return None
        data = json.loads(path.read_text())
        return data if isinstance(data, dict) else None

    def run_summary(self, job_id: int) -> dict[str, Any] | None:
        """How the arena run went (``run.json``), None before it ended or when the file cannot be read."""
        try:
            data = json.loads((self.folder(job_id) / "run.json").read_text())
        except (OSError, ValueError):
            return None
        return data if isinstance(data, dict) else None

    def script_log(self, job_id: int) -> bytes:
        """The script's output as the run left it (``script.log``; empty when there is none)."""
        try:
            return (self.folder(job_id) / "script.log").read_bytes()
        except OSError:
            return b""

    def listing(self, job_id: int) -> list[ResultFile]:
        """The job's result files that exist, in :data:`RESULT_FILES` order."""
        folder = self.folder(job_id)
        listed = [ResultFile(name, (folder / name).stat().st_size, what)
                  for name, what in RESULT_FILES.items() if (folder / name).is_file()]
        return listed + _sweep_listing(folder)

    def video_to_come(self, job: Job, listed: list[ResultFile]) -> ResultFile | None:
        """The video as a download to offer although it is not made yet: the run ended and left a recording, the
        exports are not writing and did not make it (it is rendered on the first request, :meth:`video`)."""
        names = {f.name for f in listed}
        if VIDEO in names or RECORDING not in names or job.state not in FINAL or job.exports == ExportState.WRITING:
            return None
        return ResultFile(VIDEO, None, RESULT_FILES[VIDEO] + " (made when first downloaded)")

    def path(self, job: Job, name: str) -> Path:
        """The path of result file ``name`` of ``job`` (one of :data:`RESULT_FILES`): NotFound (404) for another
        name or a file not there, Unavailable (503) for an export still being written. ``video.mp4`` is made
        from the recording on its first request (:meth:`video`)."""
        if name == VIDEO:
            return self.video(job)
        sweep = _sweep_path(self.folder(job.id), name) if job.sweep is not None else None
        if sweep is not None:
            if not sweep.is_file():
                raise NotFound(f"job {job.id} has no {name} (yet)", "name")
            return sweep
        if name not in RESULT_FILES:
            raise NotFound(f"no result file called {name[:100]!r}", "name")
        path = self.folder(job.id) / name
        if not path.is_file():
            if job.exports == ExportState.WRITING and name in EXPORT_FILES:
                raise Unavailable(f"job {job.id}'s exports are still being written: {name} is not ready yet", "name")
            raise NotFound(f"job {job.id} has no {name} (yet)", "name")
        return path

    def video(self, job: Job) -> Path:
        """The job's ``video.mp4`` (top-down, H.264): written with the job's exports (:mod:`.exports`; 503 while
        they are being written); if they did not write it, rendered from its recording on the first request
        (:func:`~swarmdeck.console.recording.export_video.export_video`, one at a time) and kept; 404 while the
        job is not over or has no recording, 503 when it cannot be made."""
        from swarmdeck.console.recording.export_video import VideoExportError, export_video
        from swarmdeck.console.recording.reader import RecordingError, open_recording

        folder = self.folder(job.id)
        out, recording = folder / VIDEO, folder / RECORDING
        if out.is_file():
            return out
        if job.exports == ExportState.WRITING:
            raise Unavailable(f"job {job.id}'s exports are still being written: the video follows the CSV and "
                              "the replay", "name")
        if job.state not in FINAL or not recording.is_file():
            raise NotFound(f"job {job.id} has no video (yet): it is made from the recording once the run is over",
                           "name")
        with self._video_lock:
            if not out.is_file():
                try:
                    with open_recording(recording) as rec:
                        export_video(rec, out)
                except (RecordingError, VideoExportError, OSError) as exc:
                    raise Unavailable(f"the video of job {job.id} could not be made: {exc}", "name") from None
        return out

    def delete(self, job_id: int) -> None:
        """Delete the job's folder and everything in it (the retention sweep)."""
        shutil.rmtree(self.folder(job_id), ignore_errors=True)


def _sweep_listing(folder: Path) -> list[ResultFile]:
    """A sweep job's outputs (:data:`.sweep_job.SWEEP_FILES`) that exist; none for another job."""
    from swarmdeck.console.portal.sweep_job import SWEEP_DIR, SWEEP_FILES

    out = folder / SWEEP_DIR
    if not out.is_dir():
        return []
    return [ResultFile(name, (out / rel).stat().st_size, what)
            for name, (rel, what) in SWEEP_FILES.items() if (out / rel).is_file()]


def _sweep_path(folder: Path, name: str) -> Path | None:
    from swarmdeck.console.portal.sweep_job import file_path

    return file_path(folder, name)
