"""One background service thread's lifecycle: start, stop event, stop and join, the error that ended it.

Every long-running helper thread in swarmdeck (listeners, camera grabbers, the command streamer, the
simulated firmware fleet, the viewer and relay servers, the player, the recorder's writer) has the same
life: started once (idempotently), told to stop through an event it waits on, joined with a bound, and
closed more than once without harm. :class:`ServiceThread` is that life, once; its owner keeps its own
``start``/``close`` API and composes one (or several) of these.

An exception that escapes the target ends the thread; it is kept in :attr:`ServiceThread.error` and
reported — to the owner's ``on_error`` (which typically counts it in the owner's health), or else on
stderr as an uncaught thread exception would be. It never propagates into the thread that stops it.
"""
from __future__ import annotations

import sys
import threading
import traceback
from collections.abc import Callable


class ServiceThread:
    """A daemon thread running ``target`` until asked to stop.

    Args:
        target: the thread's body, called with no arguments; it should return soon after
            :attr:`stop_event` is set (wait on it with :meth:`wait` instead of sleeping).
        name: the thread's name (shown in tracebacks and ``threading.enumerate()``).
        join_timeout: how long :meth:`stop` waits for the thread to end, s (None: until it ends).
        on_error: called once, in the service thread, with the exception that ended ``target``;
            default: the traceback is printed on stderr.
        wake: called by :meth:`stop` after setting the stop event, to unblock a target that waits on
            something other than the event (an event loop, a blocking server); its exceptions are
            ignored (the target may already have ended).
    """

    def __init__(self, target: Callable[[], object], name: str, *, join_timeout: float | None = 2.0,
                 on_error: Callable[[BaseException], None] | None = None,
                 wake: Callable[[], object] | None = None) -> None:
        self._target = target
        self.name = name
        self.join_timeout = join_timeout
        self._on_error = on_error
        self._wake = wake
        self._lock = threading.Lock()
        self._thread: threading.Thread | None = None
        #: Set when the thread should end; targets check it or :meth:`wait` on it.
        self.stop_event = threading.Event()
        #: The exception that ended the last run of the target, if any.
        self.error: BaseException | None = None

    # ---------------------------------------------------------------- state
    @property
    def started(self) -> bool:
        """True from :meth:`start` until a :meth:`stop` that saw the thread end (even if the target
        returned by itself earlier)."""
        return self._thread is not None

    @property
    def alive(self) -> bool:
        """True while the thread runs."""
        th = self._thread
        return th is not None and th.is_alive()

    @property
    def stopping(self) -> bool:
        """True once :meth:`stop` was called (until the next :meth:`start`)."""
        return self.stop_event.is_set()

    def wait(self, seconds: float | None) -> bool:
        """Sleep up to ``seconds`` s, waking early when asked to stop; True if asked to stop."""
        return self.stop_event.wait(seconds)

    # ---------------------------------------------------------------- lifecycle
    def start(self) -> ServiceThread:
        """Start the thread (idempotent: a started thread is left alone). After :meth:`stop` it
        may be started again, as a new thread."""
        with self._lock:
            if self._thread is not None:
                return self
            self.stop_event.clear()
            self.error = None
            self._thread = threading.Thread(target=self._run, name=self.name, daemon=True)
            self._thread.start()
        return self

    def _run(self) -> None:
        try:
            self._target()
        except BaseException as exc:  # noqa: BLE001 - captured and reported, never lost
            self.error = exc
            if self._on_error is not None:
                self._on_error(exc)
            else:
                print(f"swarmdeck: service thread {self.name!r} failed:", file=sys.stderr)
                traceback.print_exception(type(exc), exc, exc.__traceback__, file=sys.stderr)

    def stop(self, timeout: float | None = None) -> bool:
        """Set the stop event, wake the target and join it (up to ``timeout`` s, default
        ``join_timeout``). Idempotent. True when the thread has ended (or never ran); a call from
        the service thread itself does not join. A thread that outlives the join stays :attr:`started`
        (a later :meth:`start` does not run a second one; a later :meth:`stop` joins it again)."""
        self.stop_event.set()
        th = self._thread
        if th is None:
            return True
        if self._wake is not None:
            try:
                self._wake()
            except Exception:  # noqa: BLE001 - the target may already be gone
                pass
        if th is threading.current_thread():
            return False
        th.join(self.join_timeout if timeout is None else timeout)
        if th.is_alive():
            return False
        with self._lock:
            if self._thread is th:
                self._thread = None
        return True

    close = stop
