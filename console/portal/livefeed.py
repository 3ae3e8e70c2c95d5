"""The running job's newest Frame, for the live view: a sequence number and the Frame, thread-safe.

The arena runner calls :meth:`LiveFeed.publish` from its control-loop thread
after every tick (it only stores a reference: never slows the loop) and
:meth:`LiveFeed.clear` when the job ends. Readers (the pages' live view) call
:meth:`LiveFeed.latest` — ``(seq, job_id, frame)`` — or block in
:meth:`LiveFeed.wait_newer` until ``seq`` grows. ``seq`` only ever increases
(also across jobs), so a reader that remembers it never sees a Frame twice.
A researcher may watch only their own job: check ``job_id`` against the job's
owner through the service before showing the Frame.
"""
from __future__ import annotations

import threading
from typing import Any


class LiveFeed:
    def __init__(self) -> None:
        self._cond = threading.Condition()
        self._seq = 0
        self._job: int | None = None
        self._frame: Any = None
        self._jobs: dict[int, tuple[int, Any]] = {}  # several arenas: each running job's newest (seq, Frame)

    def publish(self, job_id: int, frame: Any) -> None:
        """The newest Frame of job ``job_id`` (called on the loop thread)."""
        with self._cond:
            self._seq += 1
            self._job, self._frame = int(job_id), frame
            self._jobs[int(job_id)] = (self._seq, frame)
            self._cond.notify_all()

    def clear(self, job_id: int | None = None) -> None:
        """Job ``job_id`` ended (None: every job): the next reader of it sees ``(seq, None, None)`` — of
        :meth:`latest` too when it was the newest publisher."""
        with self._cond:
            self._seq += 1
            if job_id is None:
                self._jobs.clear()
            else:
                self._jobs.pop(int(job_id), None)
            if job_id is None or self._job == int(job_id):
                self._job, self._frame = None, None
            self._cond.notify_all()

    def latest_of(self, job_id: int) -> tuple[int, int | None, Any]:
        """``(seq, job_id, frame)`` of job ``job_id`` (several arenas publish into one feed); job_id and frame
        None when it is not running."""
        with self._cond:
            seq, frame = self._jobs.get(int(job_id), (self._seq, None))
            return seq, (None if frame is None else int(job_id)), frame

    def latest(self) -> tuple[int, int | None, Any]:
        """``(seq, job_id, frame)``; job_id and frame are None when no job runs."""
        with self._cond:
            return self._seq, self._job, self._frame

    def wait_newer(self, seq: int, timeout: float) -> tuple[int, int | None, Any]:
        """Block until the sequence number passes ``seq`` (or ``timeout`` s), then :meth:`latest`."""
        with self._cond:
            self._cond.wait_for(lambda: self._seq > seq, timeout)
            return self._seq, self._job, self._frame
