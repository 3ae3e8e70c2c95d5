"""A job's exports — CSV, HTML replay, MP4 video — written after its run, off the arena thread.

The arena runner hands an ended job with a recording to :meth:`JobExports.submit`
and takes the next job at once. :class:`JobExports` is one thread with a queue of
job ids; for each it starts this module as a child process
(``python -m swarmdeck.console.portal.exports DIR/jobs/<id> --parent PID``) that
writes, from ``recording.mcap``:

* ``robots.csv`` and ``frames.csv`` (:func:`~swarmdeck.console.recording.export_csv.export_csv`),
* ``replay.html`` (:func:`~swarmdeck.console.web.export_html.export_html`),
* ``video.mp4`` (:func:`~swarmdeck.console.recording.export_video.export_video`),
* ``capsule.zip`` (:func:`~swarmdeck.console.recording.capsule_zip.write_capsule`: the script files with their
  SHA-256, the run's settings and versions, and the recording; ``swarmdeck run capsule.zip`` re-executes it), when
  the recording carries a capsule,

each into ``.exports/`` first and then renamed into the job's folder, so a file
is listed (:meth:`.PortalService.files`) only once it is whole, and the
downloads appear one after another. The child runs at a lower priority
(``nice`` +10: the arena's loop and the verification come first), dies with the
server (``PR_SET_PDEATHSIG``), and whatever it prints (viser's banner) stays out
of the server's log.

The job's ``exports`` field says where they are: ``"writing"`` (queued or being
written), ``"ready"``, ``"failed"`` (``run.json``'s ``export_error`` says what
failed; the files that were made are kept), or None (the job left no recording).
``run.json`` also gets ``exports_s`` (wall s the child took) and ``exports``
(the files written). A server stopped (or killed) while exports are being
written leaves them ``"writing"``: :meth:`JobExports.resume` redoes them on the
next start. :meth:`JobExports.stop` kills the child at once (shutdown never waits
for a video).
"""
from __future__ import annotations

import argparse
import json
import os
import queue
import shutil
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from swarmdeck.console.portal.files import UMASK, private_dir, write_private
from swarmdeck.console.portal.job import ExportState
from swarmdeck.core.service_thread import ServiceThread

if TYPE_CHECKING:
    from swarmdeck.console.portal.service import PortalService

#: what the exports write into the job's folder, in order (robots.csv and frames.csv together)
EXPORT_FILES = ("robots.csv", "frames.csv", "replay.html", "video.mp4", "capsule.zip")
STAGING = ".exports"
RESULT_MARK = "swarmdeck-exports: "  # the child's last line on stdout: this and a JSON object
NICE = 10
HTML_FPS = 10.0


def update_run_json(folder: Path, **fields: Any) -> dict[str, Any]:
    """Add ``fields`` to the job's ``run.json`` (atomically: written aside, then renamed); the new content."""
    path = folder / "run.json"
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        data = {}
    data.update(fields)
    write_run_json(folder, data)
    return data


def without_server_paths(value: Any, folder: Path) -> Any:
    """``value`` (JSON-like) with the server's paths taken out of its strings: the job's folder (and the data
    folder it is in) and the sandbox's per-run folder, so a researcher's files name only their own files."""
    from swarmdeck.console.sandbox.verification import without_run_folder

    if isinstance(value, str):
        data = folder.parent.parent
        for prefix in {str(p) for p in (folder, folder.resolve(), data, data.resolve())}:
            value = value.replace(prefix + "/", "").replace(prefix, "")
        return without_run_folder(value)
    if isinstance(value, dict):
        return {k: without_server_paths(v, folder) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [without_server_paths(v, folder) for v in value]
    return value


def write_run_json(folder: Path, data: dict[str, Any]) -> None:
    """Replace the job's ``run.json`` by ``data`` (server paths taken out: :func:`without_server_paths`)
    atomically (written aside, then renamed)."""
    path = folder / "run.json"
    tmp = path.with_suffix(".tmp")
    write_private(tmp, json.dumps(without_server_paths(data, folder), indent=1))
    tmp.replace(path)


def write_exports(folder: Path, video: bool = True) -> dict[str, Any]:
    """Write the exports of ``folder/recording.mcap`` into ``folder`` (module docstring), each file whole or not
    at all; ``{"files": [names written], "errors": [one line per export that failed]}``. A failed export does
    not stop the next one."""
    from swarmdeck.console.recording.export_csv import export_csv
    from swarmdeck.console.recording.reader import open_recording

    staging = folder / STAGING
    shutil.rmtree(staging, ignore_errors=True)  # a killed export's leftovers
    private_dir(staging)
    files: list[str] = []
    errors: list[str] = []

    def publish(*names: str) -> None:
        for name in names:
            (staging / name).replace(folder / name)
            files.append(name)

    def attempt(what: str, make: Callable[[], Any], *names: str) -> None:
        try:
            make()
            publish(*names)
        except Exception as exc:  # noqa: BLE001 - every export is tried; each failure is reported by name
            errors.append(f"{what}: {type(exc).__name__}: {exc}"[:1000])

    try:
        with open_recording(folder / "recording.mcap") as rec:
            if rec.empty:
                return {"files": [], "errors": ["the recording holds no readable frame"]}
            attempt("capsule", lambda: _capsule(folder / "recording.mcap", staging / "capsule.zip", publish))
            attempt("CSV", lambda: export_csv(rec, staging), "robots.csv", "frames.csv")
            attempt("HTML replay", lambda: _html(rec, staging / "replay.html"), "replay.html")
            if video:
                attempt("video", lambda: _video(rec, staging / "video.mp4"), "video.mp4")
    except Exception as exc:  # noqa: BLE001 - an unreadable recording: reported, never raised
        errors.append(f"recording: {type(exc).__name__}: {exc}"[:1000])
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return {"files": files, "errors": errors}


def _capsule(recording: Path, out: Path, publish: Callable[..., None]) -> None:
    """``capsule.zip`` of a recording that carries a capsule (one recorded before capsules: none, no error)."""
    from swarmdeck.console.recording.capsule_zip import read_recorded_capsule, write_capsule

    recorded = read_recorded_capsule(recording)
    if recorded.manifest is not None:
        write_capsule(recording, out, capsule=recorded)
        publish(out.name)


def _html(rec: Any, out: Path) -> None:
    from swarmdeck.console.web.export_html import export_html

    export_html(rec, out, fps=HTML_FPS)


def _video(rec: Any, out: Path) -> None:
    from swarmdeck.console.recording.export_video import export_video

    export_video(rec, out)


class JobExports:
    """The exports of ended jobs, one job at a time in a child process (module docstring).

    ``video``: also write ``video.mp4`` (else it is made on its first download).
    ``jobs_done``: jobs whose exports ended (ready or failed) since this object was made.
    """

    def __init__(self, service: PortalService, *, video: bool = True) -> None:
        self.service, self.video = service, bool(video)
        self._queue: queue.Queue[int | None] = queue.Queue()
        self._lock = threading.Lock()
        self._thread = ServiceThread(self._run, "swarmdeck-portal-exports", join_timeout=5.0, wake=self._wake)
        self._proc: subprocess.Popen[str] | None = None
        self._busy = 0  # jobs queued or being written
        self._idle = threading.Condition(self._lock)
        self.jobs_done = 0

    def submit(self, job_id: int) -> None:
        """Write the exports of ended job ``job_id`` (its ``exports`` becomes ``"writing"`` now)."""
        self.service.set_exports(int(job_id), ExportState.WRITING)
        self._enqueue(int(job_id))

    def resume(self) -> list[int]:
        """On start: the jobs whose exports a stopped server left ``"writing"``, queued again; their ids."""
        ids = self.service.exports_in(ExportState.WRITING)
        for job_id in ids:
            self._enqueue(job_id)
        return ids

    def wait_idle(self, timeout: float) -> bool:
        """Block until no export is queued or being written (or ``timeout`` s); True when idle."""
        deadline = time.monotonic() + timeout
        with self._idle:
            while self._busy:
                left = deadline - time.monotonic()
                if left <= 0:
                    return False
                self._idle.wait(left)
        return True

    def stop(self, timeout: float = 5.0) -> None:
        """Stop now: the export being written is killed (and left ``"writing"``, redone on the next start)."""
        self._thread.stop(timeout)

    def _wake(self) -> None:
        """Unblock the thread: end its wait on the queue, kill the export process it waits for."""
        self._queue.put(None)
        with self._lock:
            proc = self._proc
        if proc is not None and proc.poll() is None:
            proc.kill()

    def _enqueue(self, job_id: int) -> None:
        with self._lock:
            if self._thread.stopping:
                return
            self._busy += 1
            self._thread.start()  # the first export starts the thread (idempotent)
        self._queue.put(job_id)

    def _run(self) -> None:
        while not self._thread.stopping:
            job_id = self._queue.get()
            if job_id is None or self._thread.stopping:
                break
            try:
                self._export(job_id)
            except Exception as exc:  # noqa: BLE001 - the thread goes on with the next job; the job says why
                self._finish(job_id, {"files": [], "errors": [f"{type(exc).__name__}: {exc}"]}, 0.0)
            finally:
                with self._idle:
                    self._busy -= 1
                    self._idle.notify_all()

    def _export(self, job_id: int) -> None:
        folder = self.service.job_dir(job_id)
        if not (folder / "recording.mcap").is_file():
            self._finish(job_id, {"files": [], "errors": ["the job has no recording"]}, 0.0)
            return
        command = [sys.executable, "-m", "swarmdeck.console.portal.exports", str(folder.resolve()),
                   "--parent", str(os.getpid())] + ([] if self.video else ["--no-video"])
        t = time.monotonic()
        with self._lock:
            if self._thread.stopping:
                return
            self._proc = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                          stderr=subprocess.STDOUT, text=True, errors="replace", cwd="/")
        try:
            output, _ = self._proc.communicate()
        finally:
            with self._lock:
                code, self._proc = self._proc.returncode, None
        if self._thread.stopping:
            return  # killed by stop(): still "writing", redone on the next start
        result = _result(output)
        if result is None:
            tail = " | ".join(output.strip().splitlines()[-3:])[-1000:]
            result = {"files": [], "errors": [f"the export process ended with code {code}: {tail}"]}
        self._finish(job_id, result, time.monotonic() - t)

    def _finish(self, job_id: int, result: dict[str, Any], wall_s: float) -> None:
        errors = result["errors"]
        update_run_json(self.service.job_dir(job_id), exports=result["files"], exports_s=round(wall_s, 3),
                        export_error="; ".join(errors) if errors else None)
        self.service.set_exports(job_id, ExportState.FAILED if errors else ExportState.READY)
        self.jobs_done += 1


def _result(output: str) -> dict[str, Any] | None:
    for line in reversed(output.splitlines()):
        if line.startswith(RESULT_MARK):
            try:
                data = json.loads(line[len(RESULT_MARK):])
            except ValueError:
                return None
            return data if isinstance(data, dict) and {"files", "errors"} <= data.keys() else None
    return None


def main(argv: list[str] | None = None) -> int:
    """The child: ``FOLDER --parent PID [--no-video]``; prints :data:`RESULT_MARK` and the result last."""
    parser = argparse.ArgumentParser(prog="python -m swarmdeck.console.portal.exports")
    parser.add_argument("folder", type=Path)
    parser.add_argument("--parent", type=int, required=True)
    parser.add_argument("--no-video", action="store_true")
    args = parser.parse_args(argv)
    from swarmdeck.console.sandbox.namespaces import die_with_parent

    die_with_parent(args.parent)
    os.umask(UMASK)  # what the exporters write is the researcher's: 0600 (files.py), whoever started us
    os.nice(NICE)
    result = write_exports(args.folder, video=not args.no_video)
    print(RESULT_MARK + json.dumps(result), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
