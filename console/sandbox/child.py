"""The sandboxed side: runs a user's script with robots that live on the other side of a pipe.

Forked by the fork server (:mod:`swarmdeck.console.sandbox.zygote`) inside its ``unshare``
jail, or started by :mod:`swarmdeck.console.sandbox.run` as
``python -m swarmdeck.console.sandbox.child IN_FD OUT_FD`` inside bubblewrap. It
reads the ``start`` message, applies its resource limits, drops to its run's own uid
(when started as root), loads the seccomp filter (:mod:`swarmdeck.console.sandbox.seccomp`;
bubblewrap has loaded it already), and runs the script with
:func:`swarmdeck.devices.runner.run_experiment`: both ``experiment(arena)``
scripts and unmodified rps scripts work, because every Arena the script builds
(directly or through the rps ``Robotarium``) gets :class:`PipeRobots` as its
robots. The child's Arena computes the script's nominal velocities and hands them
over as they are: the trusted side owns the simulator (or the robots), the wheel
limits, the filter, the validation and the recording, and treats everything this
process sends as untrusted.
"""
from __future__ import annotations

import json
import os
import sys
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.console.sandbox.import_policy import install as install_import_policy
from swarmdeck.console.sandbox.network_link import RemoteNetwork, network_config_message
from swarmdeck.console.sandbox.protocol import (
    MAX_NETWORK_LINKS,
    MESSAGE,
    FrameReader,
    decode,
    encode_annotations,
    encode_commands,
    pack,
    write_frame,
)
from swarmdeck.console.sandbox.protocol import poses as read_poses
from swarmdeck.console.sandbox.senses import leds_message, readings_from_message, sensing_message
from swarmdeck.core.annotations import EMPTY as EMPTY_ANNOTATIONS
from swarmdeck.core.annotations import Annotations
from swarmdeck.core.kinematics import GritsBotParams, unicycle_to_si
from swarmdeck.core.ports import SensedPoses
from swarmdeck.devices.arena import ExperimentFinished
from swarmdeck.devices.experiment_params import METRICS_SINK, PARAMS_ENV
from swarmdeck.devices.runner import RunnerArenaError, ScriptError, run_experiment
from swarmdeck.devices.simulator import ArenaConfig
from swarmdeck.network import NetworkConfig
from swarmdeck.sensing import SensingConfig, SensorReadings


class Link:
    """The child's end of the pipe."""

    def __init__(self, in_fd: int, out_fd: int) -> None:
        self.reader = FrameReader(in_fd)
        self.out_fd = out_fd
        self.arenas = 0

    def send(self, frame: bytes | dict[str, Any]) -> None:
        write_frame(self.out_fd, frame)

    def receive(self) -> tuple[bytes, bytes]:
        return self.reader.read_blocking()

    def message(self) -> dict[str, Any]:
        kind, body = self.receive()
        if kind != MESSAGE:
            raise RuntimeError(f"the trusted side sent a {kind!r} frame where a message was expected")
        return decode(body)


class MetricsBox:
    """The metrics the script recorded (``record_metrics``): the last value of each name, and whether any changed
    since they were last sent (they go to the trusted side before a tick's commands and with ``done``)."""

    def __init__(self) -> None:
        self.values: dict[str, float] = {}
        self.changed = False

    def record(self, values: dict[str, float]) -> None:
        self.values.update(values)
        self.changed = True

    def take(self) -> dict[str, float] | None:
        """The values when they changed since the last call, else None."""
        if not self.changed:
            return None
        self.changed = False
        return dict(self.values)


class PipeRobots:
    """Robot ports (:mod:`swarmdeck.core.ports`) whose robots are on the trusted side: a
    :class:`~swarmdeck.core.ports.NominalSink`.

    The Arena hands it the nominal look-ahead velocities (:meth:`send_nominal`) before any
    wheel limit or filter: those run once, on the trusted side, as in an in-process run.
    """

    name = "the trusted side's robots"

    def __init__(self, link: Link, n_robots: int | None, initial_poses: ArrayLike | None, *,
                 config: ArenaConfig, params: GritsBotParams, metrics: MetricsBox | None = None) -> None:
        link.arenas += 1
        if link.arenas > 1:
            raise RuntimeError("a sandboxed script may build one Arena (or Robotarium) per run")
        ic = None if initial_poses is None else np.asarray(initial_poses, dtype=float)
        n = int(ic.shape[0]) if ic is not None else int(n_robots)
        self.link, self.n_robots, self.params, self.config = link, n, params, config
        self._ids = np.arange(n, dtype=np.int64)
        self._seen = np.ones(n, dtype=bool)
        self._metrics = metrics
        self._network: Any = None  # a decentralised run's swarmdeck.network.Network (attach_network)
        self._drawn: dict[str, Any] = encode_annotations(EMPTY_ANNOTATIONS)
        self._drawn_from: Annotations | None = None  # the drawing last encoded (the Arena's annotator keeps one
        # object while the drawing is unchanged: then nothing is encoded or compared, bench/RESULTS.md "sandbox per tick")
        self._readings: SensorReadings | None = None
        self._remote: RemoteNetwork | None = None  # a decentralised run's network stand-in (remote_network)
        arena: dict[str, Any] = {"t": "arena", "n": n, "initial": None if ic is None else pack(ic)}
        if config.obstacles is not None:  # the script's own (an rps 2.x Robotarium(obstacles=...)): solid on the trusted side
            arena["obstacles"] = pack(config.obstacles.segments)
            arena["m"] = int(config.obstacles.m)
        link.send(arena)
        self._take()

    def _take(self) -> None:
        while True:
            kind, body = self.link.receive()
            if kind != MESSAGE:
                break
            message = decode(body)
            if message["t"] == "readings":  # what the robots sensed, computed on the trusted side (senses.py)
                self._readings = readings_from_message(message)
                continue
            if message["t"] == "inboxes" and self._remote is not None:  # the trusted network's deliveries
                self._remote.deliver(message)
                continue
            if message["t"] == "end":
                raise ExperimentFinished(str(message.get("reason", "the run is over")))
            raise RuntimeError(f"unexpected message from the trusted side: {message['t']!r}")
        self._k, self._time, self._poses = read_poses(body, self.n_robots)

    #: every decentralised run's controllers each in their own process (devices/isolated_controllers.py)
    isolate_controllers = True

    def remote_network(self, config: NetworkConfig) -> RemoteNetwork:
        """The network of a decentralised run (``devices.decentralised``): modelled on the trusted side
        (console/sandbox/network_link.py); returns the stand-in the controllers use, after the trusted side's first
        topology arrived."""
        if self._remote is not None:
            raise RuntimeError("a sandboxed script may run one decentralised experiment per Arena")
        self._remote = RemoteNetwork(self.n_robots, config)
        self.link.send(network_config_message(config))
        kind, body = self.link.receive()  # the trusted side answers at once with the first topology
        message = decode(body) if kind == MESSAGE else {}
        if message.get("t") != "inboxes":
            raise RuntimeError("the trusted side did not answer the network's configuration")
        self._remote.deliver(message)
        return self._remote

    def use_sensors(self, config: SensingConfig | None) -> None:
        """The script's sensors: the trusted side simulates them (or reads the robots' own) and sends the readings
        with every tick's poses (:class:`~swarmdeck.core.ports.SensesElsewhere`)."""
        if config is None:
            self.link.send({"t": "sensors", "config": None})
            self._readings = None
            return
        self.link.send(sensing_message(config))

    def sensor_readings(self) -> SensorReadings | None:
        """The trusted side's readings of the last tick (None before the first)."""
        return self._readings

    def set_leds(self, ids: NDArray[np.int64], rgb: NDArray[np.uint8]) -> None:
        """The LEDs as the script set them ``(N, 3)`` (the Arena passes every robot's): shown on the trusted side."""
        full = np.zeros((self.n_robots, 3), dtype=np.uint8)
        full[np.asarray(ids, dtype=np.int64)] = rgb
        self.link.send(leds_message(full))

    def read(self, now: float = 0.0) -> SensedPoses:
        """The poses and time the trusted side sent last (every robot seen)."""
        return SensedPoses(self._ids, self._poses.copy(), self._seen, time=self._time)

    def attach_network(self, network: Any) -> None:
        """A decentralised run's network (``devices.decentralised``): its traffic goes to the trusted side, which shows
        and records it, before every tick's commands."""
        self._network = network

    def send_nominal(self, ids: NDArray[np.int64], nominal: NDArray[np.float64]) -> None:
        """Send the nominal ``(N, 2)`` for the current poses; waits for the next poses."""
        if self._remote is not None:  # what the controllers sent: the trusted network checks and delivers it
            self.link.send({"t": "outbox", "k": self._k, "messages": self._remote.take_outgoing()})
        elif self._network is not None:
            traffic = self._network.traffic()
            if len(traffic.links) <= MAX_NETWORK_LINKS:
                self.link.send({"t": "network", "k": self._k, "links": pack(traffic.links.astype(float)),
                                "rate": pack(traffic.messages / self.config.dt)})
        values = None if self._metrics is None else self._metrics.take()
        if values is not None:
            self.link.send({"t": "metrics", "k": self._k, "values": values})
        self.link.send(encode_commands(self._k, nominal))
        self._take()

    def send_annotations(self, ann: Annotations) -> None:
        """What the script draws from this tick on (``Arena.draw``), sent before the commands — only when it
        changed since the last tick."""
        if ann is self._drawn_from:
            return
        self._drawn_from = ann
        message = encode_annotations(ann)
        if message != self._drawn:
            self.link.send(message)
            self._drawn = message

    def send(self, ids: NDArray[np.int64], v: ArrayLike, w: ArrayLike) -> None:
        """Unicycle commands (for callers without the nominal): sent as the velocities they give."""
        u = unicycle_to_si(self._poses, np.asarray(v, dtype=float).reshape(-1), np.asarray(w, dtype=float).reshape(-1),
                           self.params.lookahead)
        self.send_nominal(ids, u)

    def hold(self) -> None:
        """Nothing to do: the trusted side owns the robots."""

    def health(self) -> str:
        return f"t = {self._time:.1f} s"

    def close(self) -> None:
        """Nothing to release: the trusted side stops the robots."""


def _confine(start: dict[str, Any]) -> None:
    """Limits first, then the uid, then the seccomp filter (when the ``start`` message asks for it:
    bubblewrap loads it itself): from here on nothing the script does can undo them."""
    import resource

    for name, value in start.get("rlimits", {}).items():
        which = getattr(resource, name)
        if name == "RLIMIT_CPU":
            resource.setrlimit(which, (value, value + 5))  # SIGXCPU at the soft limit, SIGKILL at the hard
        else:
            resource.setrlimit(which, (value, value))
    if sys.platform == "linux":  # no setuid binary can give the script privileges back
        import ctypes

        ctypes.CDLL(None).prctl(38, ctypes.c_ulong(1), ctypes.c_ulong(0), ctypes.c_ulong(0), ctypes.c_ulong(0))
    uid = start.get("uid")
    if uid is not None:
        os.setgroups([])
        os.setresgid(uid, uid, uid)
        os.setresuid(uid, uid, uid)
    if start.get("seccomp"):
        from swarmdeck.console.sandbox.seccomp import filter_program, install

        install(filter_program())


def main(argv: list[str]) -> int:
    link = Link(int(argv[0]), int(argv[1]))
    start = link.message()
    scratch = start.get("scratch")
    if scratch:
        os.chdir(scratch)
        os.environ.update(HOME=scratch, TMPDIR=scratch)
    _confine(start)
    env = start.get("script_env")
    if env:  # the lab's script environment: from here on the script imports only what it lists
        install_import_policy(env["site"], env["modules"], [os.path.dirname(os.path.abspath(start["script"]))])
    if start.get("params") is not None:  # the sweep's values: swarmdeck.devices.params() reads them
        os.environ[PARAMS_ENV] = json.dumps(start["params"])
    metrics = MetricsBox()
    METRICS_SINK.set(metrics.record)
    link.send({"t": "ready"})
    error: str | None = None
    error_line: str | None = None
    try:
        result = run_experiment(
            start["script"], n_robots=start.get("n_robots"), duration=start.get("duration"), seed=None,
            safety=False, rps=start.get("rps"), argv=[str(a) for a in start.get("argv") or []],
            rps_semantics=bool(start.get("rps_semantics", False)), rps_call_order=bool(start.get("rps_call_order", True)),
            bounds=tuple(start["bounds"]) if start.get("bounds") else None,
            robot_model=start.get("robot_model"), rps_generation=start.get("rps_generation"),
            backend_factory=lambda n, ic, config, params: PipeRobots(link, n, ic, config=config, params=params,
                                                                     metrics=metrics),
        )
        error, error_line = result.error, result.error_line
    except (ScriptError, RunnerArenaError) as exc:
        error = error_line = str(exc)
    except EOFError:
        return 0  # the trusted side ended the run and closed the pipe
    try:
        import resource

        usage = resource.getrusage(resource.RUSAGE_SELF)
        link.send({"t": "done", "error": error, "error_line": error_line, "cpu_s": usage.ru_utime + usage.ru_stime,
                   "metrics": metrics.values})
    except OSError:
        pass
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
