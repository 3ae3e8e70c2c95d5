"""Decentralised isolation: each robot's controller in its own process, so no robot's controller can read another's
memory (issue 28.2).

In one interpreter, robots' controllers share everything the script defines — a module global, a closure, a class
attribute, ``sys.modules`` — and a controller could pass robot 0's pose to robot 1 through it, past the network.
:class:`ProcessControllers` forks one worker per robot once (before the first tick): from then on robot ``i``'s
controller runs only in worker ``i``, which receives robot ``i``'s own view each tick (pose, time, tick, inbox,
readings, neighbours) and answers with its command and its outbox; its ``view.state`` and anything it writes to a
global stay in its own memory. A controller that relies on something another robot's controller wrote finds its
own copy (an exception there is counted, named and that robot stops, with a hint that globals are not shared).

Workers are sealed Arenas: ``arena.poses()``, ``arena.step()``… raise
:class:`~swarmdeck.network.errors.IsolationError` in them. They end when their pipe closes (the script's process
ended) — in the sandbox the trusted side also kills every process of the run. The sandbox's child turns this on for
every :class:`~swarmdeck.devices.decentralised.Decentralised` run (``PipeRobots.isolate_controllers``); in process,
``Decentralised(..., isolate=True)``. Cost: one pickled request and answer per robot per tick over a pipe
(bench/bench_decentralised_isolation.py).
"""
from __future__ import annotations

import os
import pickle
import struct
import sys
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmdeck.network.view import Outbox, RobotView

__all__ = ["ISOLATION_HINT", "ControllerAnswer", "ProcessControllers"]

#: appended to a failing isolated controller's error
ISOLATION_HINT = ("(each robot's controller runs in its own process: globals, closures and class attributes are not "
                  "shared between robots; exchange information with view.send / view.broadcast)")
_LEN = struct.Struct("<I")
_MAX_ANSWER = 1 << 24  # bytes a worker may answer with in one tick (its outbox is bounded far below)

# (command (2,) floats | None, error (kind, text) | None, outbox messages [(j | None, bytes)], refusals [(reason, text)])
ControllerAnswer = tuple[NDArray[np.float64] | None, tuple[str, str] | None, list[tuple[int | None, bytes]], list[tuple[str, str]]]


def _write(fd: int, data: bytes) -> None:
    view = memoryview(_LEN.pack(len(data)) + data)
    while view:
        view = view[os.write(fd, view):]


def _read(fd: int, limit: int) -> bytes | None:
    """One length-prefixed record, None at end of file."""
    head = _exactly(fd, _LEN.size)
    if head is None:
        return None
    (size,) = _LEN.unpack(head)
    if size > limit:
        raise ValueError(f"a record of {size} bytes (at most {limit})")
    return _exactly(fd, size)


def _exactly(fd: int, size: int) -> bytes | None:
    chunks, got = [], 0
    while got < size:
        chunk = os.read(fd, size - got)
        if not chunk:
            return None
        chunks.append(chunk)
        got += len(chunk)
    return b"".join(chunks)


class ProcessControllers:
    """One forked worker per robot running ``controller(i, view)`` (see the module docstring).

    Args:
        n: robots.
        controller: ``controller(i, view) -> (2,)`` look-ahead velocity, m/s.
        limits: ``(max_message_bytes, max_messages_per_tick)`` of each robot's outbox.
        in_worker: called first thing in every worker with the robot index (the Arena seals itself there).

    RuntimeError naming the limit when the workers cannot be started (e.g. the sandbox's process limit).
    """

    def __init__(self, n: int, controller: Callable[[int, RobotView], Any], limits: tuple[int, int],
                 in_worker: Callable[[int], None] | None = None) -> None:
        self.n = int(n)
        self._controller, self._limits, self._in_worker = controller, limits, in_worker
        self._pipes: list[tuple[int, int]] = []  # (write requests, read answers) per robot
        self._pids: list[int] = []
        try:
            for i in range(self.n):
                self._start(i)
        except OSError as exc:
            self.close()
            raise RuntimeError(f"cannot run {self.n} robots' controllers in their own processes ({exc}): started "
                               f"{len(self._pids)}; the sandbox limits a run's processes (SandboxLimits.processes)") \
                from None

    def _start(self, i: int) -> None:
        req_r, req_w = os.pipe()
        ans_r, ans_w = os.pipe()
        sys.stdout.flush()
        sys.stderr.flush()
        pid = os.fork()
        if pid == 0:  # the worker: nothing of the other robots' pipes, its own copy of everything else
            code = 0
            try:
                for w, r in self._pipes:
                    os.close(w)
                    os.close(r)
                os.close(req_w)
                os.close(ans_r)
                self._serve(i, req_r, ans_w)
            except BaseException:  # noqa: BLE001 - a worker never returns into the script's code
                code = 1
            finally:
                try:
                    sys.stdout.flush()
                    sys.stderr.flush()
                finally:
                    os._exit(code)
        os.close(req_r)
        os.close(ans_w)
        self._pipes.append((req_w, ans_r))
        self._pids.append(pid)

    def _serve(self, i: int, requests: int, answers: int) -> None:
        if self._in_worker is not None:
            self._in_worker(i)
        state: dict[str, Any] = {}
        max_bytes, max_count = self._limits
        while True:
            raw = _read(requests, 1 << 30)
            if raw is None:
                return
            pose, time, tick, inbox, readings, neighbours = pickle.loads(raw)
            outbox = Outbox(i, self.n, max_bytes, max_count, len(neighbours))
            view = RobotView(i, pose, time, tick, inbox, readings, state, neighbours, outbox)
            command: Any = None
            error: tuple[str, str] | None = None
            try:
                raw = self._controller(i, view)
            except Exception as exc:  # noqa: BLE001 - the user's controller: reported, the robot stops
                error = (type(exc).__name__, f"raised {type(exc).__name__}: {exc} {ISOLATION_HINT}")
            else:
                try:
                    command = np.asarray(raw, dtype=float).reshape(2)
                except (TypeError, ValueError):
                    error = ("bad_command", f"returned {raw!r:.80}, not a velocity (2,) in m/s: stopped")
            sys.stdout.flush()
            _write(answers, pickle.dumps((command, error, list(outbox.messages), list(outbox.refusals))))

    def decide(self, views: list[tuple[Any, ...]]) -> list[ControllerAnswer]:
        """Every robot's answer to its view ``(pose (3,), time s, tick, inbox, readings, neighbours)``: all requests
        first (the workers run in parallel), then the answers in robot order."""
        for (w, _), view in zip(self._pipes, views):
            _write(w, pickle.dumps(view))
        out: list[ControllerAnswer] = []
        for i, (_, r) in enumerate(self._pipes):
            raw = _read(r, _MAX_ANSWER)
            if raw is None:
                raise RuntimeError(f"robot {i}'s controller process ended (it exited or was killed)")
            command, error, messages, refusals = pickle.loads(raw)  # noqa: S301 - the same script's own process
            out.append((command, error, messages, refusals))
        return out

    def close(self) -> None:
        """Close the pipes (the workers end) and reap them."""
        for w, r in self._pipes:
            for fd in (w, r):
                try:
                    os.close(fd)
                except OSError:
                    pass
        self._pipes = []
        for pid in self._pids:  # a worker still in its controller is killed: no wait without an end
            try:
                os.kill(pid, 9)
                os.waitpid(pid, 0)
            except (ChildProcessError, ProcessLookupError):
                pass
        self._pids = []
