"""The sandboxed side: runs a user's script with robots that live on the other side of a pipe.

Started by :mod:`swarmdeck.console.jobs.sandbox` as
``python -m swarmdeck.console.jobs.child IN_FD OUT_FD`` (inside the jail). It
reads the ``start`` message, applies its resource limits, drops to its own uid
(when started as root), and runs the script with
:func:`swarmdeck.devices.runner.run_experiment`: both ``experiment(arena)``
scripts and unmodified rps scripts work, because every Arena the script builds
(directly or through the rps ``Robotarium``) gets :class:`PipeRobots` as its
robots. The child's Arena runs without a safety filter: the trusted side owns
the simulator (or the robots), the filter, the validation and the recording, and
treats everything this process sends as untrusted.
"""
from __future__ import annotations

import os
import sys
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.console.jobs.protocol import FrameReader, floats, pack, write_frame
from swarmdeck.devices.arena import ExperimentFinished
from swarmdeck.core.kinematics import GritsBotParams
from swarmdeck.devices.runner import ScriptError, RunnerArenaError, run_experiment
from swarmdeck.devices.simulator import ArenaConfig


class Link:
    """The child's end of the pipe."""

    def __init__(self, in_fd: int, out_fd: int) -> None:
        self.reader = FrameReader(in_fd)
        self.out_fd = out_fd
        self.arenas = 0
        self.arena: Any = None  # the script's Arena, once built

    def send(self, message: dict[str, Any]) -> None:
        write_frame(self.out_fd, message)

    def receive(self) -> dict[str, Any]:
        return self.reader.read_blocking()


class PipeRobots:
    """A :class:`~swarmdeck.devices.backend.RobotBackend` whose robots are on the trusted side."""

    def __init__(self, link: Link, n_robots: int | None, initial_poses: ArrayLike | None, *,
                 config: ArenaConfig, params: GritsBotParams) -> None:
        link.arenas += 1
        if link.arenas > 1:
            raise RuntimeError("a sandboxed script may build one Arena (or Robotarium) per run")
        ic = None if initial_poses is None else np.asarray(initial_poses, dtype=float)
        n = int(ic.shape[0]) if ic is not None else int(n_robots)
        self.link, self.n_robots, self.params, self.config = link, n, params, config
        link.send({"t": "arena", "n": n, "initial": None if ic is None else pack(ic)})
        self._take(link.receive())

    def _take(self, message: dict[str, Any]) -> None:
        if message["t"] == "end":
            raise ExperimentFinished(str(message.get("reason", "the run is over")))
        self._k = int(message["k"])
        self._time = float(message["time"])
        self._poses = floats(message, "poses", (self.n_robots, 3))

    @property
    def poses(self) -> NDArray[np.float64]:
        return self._poses.copy()

    @property
    def time(self) -> float:
        return self._time

    def step(self, v: ArrayLike, w: ArrayLike) -> NDArray[np.float64]:
        # "invalid": robot-steps whose non-finite commands the script's own Arena stopped so far
        invalid = int(getattr(self.link.arena, "invalid_commands", 0))
        self.link.send({"t": "cmd", "k": self._k, "v": pack(np.asarray(v, dtype=float).reshape(-1)),
                        "w": pack(np.asarray(w, dtype=float).reshape(-1)), "invalid": invalid})
        self._take(self.link.receive())
        return self._poses.copy()


def _confine(start: dict[str, Any]) -> None:
    """Limits first, then the uid: from here on nothing the script does can raise them again."""
    import resource

    for name, value in start.get("rlimits", {}).items():
        which = getattr(resource, name)
        if name == "RLIMIT_CPU":
            resource.setrlimit(which, (value, value + 5))  # SIGXCPU at the soft limit, SIGKILL at the hard
        else:
            resource.setrlimit(which, (value, value))
    uid = start.get("uid")
    if uid is not None:
        os.setgroups([])
        os.setresgid(uid, uid, uid)
        os.setresuid(uid, uid, uid)


def main(argv: list[str]) -> int:
    link = Link(int(argv[0]), int(argv[1]))
    start = link.receive()
    scratch = start.get("scratch")
    if scratch:
        os.chdir(scratch)
        os.environ.update(HOME=scratch, TMPDIR=scratch)
    _confine(start)
    link.send({"t": "ready"})
    error: str | None = None
    error_line: str | None = None
    try:
        result = run_experiment(
            start["script"], n_robots=start.get("n_robots"), duration=start.get("duration"), seed=None,
            safety=False, rps=start.get("rps"),
            backend_factory=lambda n, ic, config, params: PipeRobots(link, n, ic, config=config, params=params),
            on_create=lambda arena: setattr(link, "arena", arena),
        )
        error, error_line = result.error, result.error_line
    except (ScriptError, RunnerArenaError) as exc:
        error = error_line = str(exc)
    except EOFError:
        return 0  # the trusted side ended the run and closed the pipe
    try:
        import resource

        usage = resource.getrusage(resource.RUSAGE_SELF)
        link.send({"t": "done", "error": error, "error_line": error_line, "cpu_s": usage.ru_utime + usage.ru_stime})
    except OSError:
        pass
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
