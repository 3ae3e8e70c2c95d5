"""The decentralised experiment style: one controller per robot that sees only what that robot could know.

``controller(i, view) -> (2,)`` is called for each robot ``i`` every tick with a
:class:`~swarmdeck.network.view.RobotView`: robot ``i``'s own pose, time and tick, its inbox, its own sensor
readings, its own persistent ``state`` and its current neighbours; it returns the velocity ``(2,)`` (m/s) of
its look-ahead point, and may ``view.send(j, …)`` / ``view.broadcast(…)``. :class:`Decentralised` owns the
:class:`~swarmdeck.network.Network` on the trusted side: after every robot's controller it forwards the
outboxes, drives the arena one step (wheel limits, barrier: the same pipeline as every Arena step) and steps the
network at the new positions, which fills the inboxes of the next tick.

Isolation: the view holds no reference to anything shared; reading anything else on it, or
``arena.poses()``/``arena.positions()``/``arena.step()`` while a controller runs, raises
:class:`~swarmdeck.network.errors.IsolationError` naming the robot and what it reached for. A controller
that raises, returns something other than a finite ``(2,)`` velocity, or sends a message the network refuses
is counted in :attr:`Decentralised.errors` (kind → count), its message kept in :attr:`Decentralised.events`,
and that robot stands still for the tick (``strict=True`` raises instead). In-process this stops honest
mistakes; the sandbox (``swarmdeck run --sandbox``, verification, the portal) is what stops a hostile script.
"""
from __future__ import annotations

from collections import Counter, deque
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.devices.arena import Arena
from swarmdeck.devices.isolated_controllers import ProcessControllers
from swarmdeck.network.config import NetworkConfig
from swarmdeck.network.errors import MessageError
from swarmdeck.network.network import Network, NetworkTraffic
from swarmdeck.network.view import Outbox, RobotView

__all__ = ["Controller", "Decentralised", "ReadingsSource", "RobotControllers"]

Controller = Callable[[int, RobotView], ArrayLike]
#: robot index -> that robot's own readings (e.g. ``SensorReadings.robot``), called on the trusted side
ReadingsSource = Callable[[int], Any]


class RobotControllers:
    """Every robot's controller over a network, without an arena: ``decide(poses, time)`` gives the commands.

    The part of :class:`Decentralised` the console's ``decentralised`` behaviour uses too. Its owner steps
    :attr:`network` at the robots' positions after the robots moved (or at the tick's positions).

    Args:
        n: number of robots.
        controller: ``controller(i, view) -> (2,)`` look-ahead velocity, m/s.
        config: the network.
        positions: ``(n, 2)`` m, for the first tick's topology.
        sensors: robot index → its readings, or None.
        strict: raise the first controller error instead of counting it and stopping that robot.
        seal: called with ``"robot i's controller"`` before robot i's controller runs and with None after
            (the Arena refuses ``poses()`` while sealed).
    """

    def __init__(self, n: int, controller: Controller, config: NetworkConfig | None = None, *,
                 positions: ArrayLike | None = None, sensors: ReadingsSource | None = None, strict: bool = False,
                 seal: Callable[[str | None], None] | None = None, network: Any = None) -> None:
        if not callable(controller):
            raise ValueError(f"controller must be a function (i, view) -> velocity, got {controller!r}")
        self.n = int(n)
        self.controller = controller
        self.config = config if config is not None else NetworkConfig()
        # ``network``: a stand-in with Network's interface (the sandbox's child: the trusted side holds the network)
        self.network = network if network is not None else Network(self.n, self.config, positions=positions)
        self.sensors = sensors
        self.strict = strict
        self.seal = seal
        self.tick = 0
        self.states: list[dict[str, Any]] = [{} for _ in range(self.n)]
        self.errors: Counter[str] = Counter()
        self.events: deque[str] = deque(maxlen=200)
        self.last_commands = np.zeros((self.n, 2))
        self.on_event: Callable[[str], None] | None = None  # also told every event (the Arena's event list)
        self.workers: ProcessControllers | None = None  # isolate(): each controller in its own process

    def isolate(self, in_worker: Callable[[int], None] | None = None) -> None:
        """From now on each robot's controller runs in its own forked process
        (:mod:`swarmdeck.devices.isolated_controllers`): no controller can read another robot's memory.
        ``in_worker(i)`` runs first in robot i's process. RuntimeError when the processes cannot be started."""
        if self.workers is None:
            self.workers = ProcessControllers(self.n, self.controller, (self.config.max_message_bytes,
                                                                        self.config.max_messages_per_tick), in_worker)

    def close(self) -> None:
        """End the controllers' processes (when isolated)."""
        if self.workers is not None:
            self.workers.close()
            self.workers = None

    def _fail(self, kind: str, text: str, exc: BaseException | None = None) -> None:
        self.errors[kind] += 1
        self.events.append(text)
        if self.on_event is not None:
            self.on_event(text)
        if self.strict:
            if exc is not None:
                raise exc
            raise ValueError(text)

    def _command(self, i: int, view: RobotView) -> NDArray[np.float64]:
        if self.seal is not None:
            self.seal(f"robot {i}'s controller")
        try:
            raw = self.controller(i, view)
        except Exception as exc:  # a user's controller: counted, the robot stops, the loop goes on
            self._fail(type(exc).__name__, f"tick {self.tick}: robot {i}'s controller raised "
                                           f"{type(exc).__name__}: {exc}", exc)
            return np.zeros(2)
        finally:
            if self.seal is not None:
                self.seal(None)
        try:
            u = np.asarray(raw, dtype=float).reshape(2)
        except (TypeError, ValueError):
            self._fail("bad_command", f"tick {self.tick}: robot {i}'s controller returned {raw!r}, "
                                      "not a velocity (2,) in m/s: stopped")
            return np.zeros(2)
        if not np.all(np.isfinite(u)):
            self._fail("bad_command", f"tick {self.tick}: robot {i}'s controller returned a non-finite "
                                      f"velocity {u.tolist()}: stopped")
            return np.zeros(2)
        return u

    def _decide_isolated(self, poses: NDArray[np.float64], time: float) -> tuple[NDArray[np.float64], list[Outbox]]:
        """:meth:`decide` with every controller in its own process (:attr:`workers`)."""
        assert self.workers is not None
        net, n = self.network, self.n
        views = [(poses[i].copy(), float(time), self.tick, net.inbox(i),
                  self.sensors(i) if self.sensors is not None else None, net.neighbours(i)) for i in range(n)]
        commands = np.zeros((n, 2))
        outboxes = []
        for i, (command, error, messages, refusals) in enumerate(self.workers.decide(views)):
            outbox = Outbox(i, n, self.config.max_message_bytes, self.config.max_messages_per_tick, 0)
            outbox.messages.extend(messages)
            outbox.refusals.extend(refusals)
            outboxes.append(outbox)
            if error is not None:
                self._fail(error[0], f"tick {self.tick}: robot {i}'s controller {error[1]}")
            elif command is None or not np.all(np.isfinite(command)):
                self._fail("bad_command", f"tick {self.tick}: robot {i}'s controller returned a non-finite "
                                          f"velocity: stopped")
            else:
                commands[i] = command
        return commands, outboxes

    def decide(self, poses: ArrayLike, time: float) -> NDArray[np.float64]:
        """Every robot's command ``(n, 2)`` m/s for ``poses`` ``(n, 3)`` at ``time`` s; their messages are queued."""
        net, cfg, n = self.network, self.config, self.n
        poses = np.asarray(poses, dtype=float).reshape(n, 3)
        if self.workers is not None:
            commands, outboxes = self._decide_isolated(poses, time)
            self._post(outboxes)
            self.last_commands = commands
            self.tick += 1
            return commands
        commands = np.zeros((n, 2))
        outboxes = []
        for i in range(n):
            neighbours = net.neighbours(i)
            outbox = Outbox(i, n, cfg.max_message_bytes, cfg.max_messages_per_tick, len(neighbours))
            readings = self.sensors(i) if self.sensors is not None else None
            view = RobotView(i, poses[i], time, self.tick, net.inbox(i), readings, self.states[i], neighbours, outbox)
            commands[i] = self._command(i, view)
            outboxes.append(outbox)
        self._post(outboxes)
        self.last_commands = commands
        self.tick += 1
        return commands

    def _post(self, outboxes: list[Outbox]) -> None:
        """Every robot's refusals counted, then its messages handed to the network."""
        net = self.network
        for outbox in outboxes:
            for reason, text in outbox.refusals:
                net.stats[f"refused:{reason}"] += 1
                net.errors.append(text)
                self.errors[f"message:{reason}"] += 1
                self.events.append(text)
        for outbox in outboxes:
            for j, data in outbox.messages:
                try:
                    if j is None:
                        net.broadcast_encoded(outbox.i, data)
                    else:
                        net.send_encoded(outbox.i, j, data)
                except MessageError as exc:  # the outbox checked the limits; a worker's answer is checked here
                    self._fail("message", str(exc))

    def report(self) -> dict[str, Any]:
        """Counts of the run: the network's (sent, delivered, lost, unreachable, over_bandwidth, refused:*)
        and the controllers' errors."""
        return {"ticks": self.tick, "network": dict(self.network.stats), "controller errors": dict(self.errors),
                "last events": list(self.events)[-5:]}


class Decentralised:
    """Run ``controller`` for every robot of ``arena`` over a network with ``config`` (see the module docstring).

    Args:
        arena: the robots.
        controller: ``controller(i, view) -> (2,)`` look-ahead velocity, m/s.
        config: the network (default: :class:`NetworkConfig` ()).
        sensors: robot index → its readings; default: ``arena.sense().robot(i)`` when the arena has sensors,
            else None.
        strict: raise the first controller error instead of counting it and stopping that robot.
        isolate: run each robot's controller in its own process (:mod:`swarmdeck.devices.isolated_controllers`):
            no controller can read another's memory; None: not in process. Robots that ask for it (the sandbox's
            ``PipeRobots.isolate_controllers``) always get it, whatever is passed here.
    """

    def __init__(self, arena: Arena, controller: Controller, config: NetworkConfig | None = None, *,
                 sensors: ReadingsSource | None = None, strict: bool = False, isolate: bool | None = None) -> None:
        self.arena = arena
        remote = getattr(arena.backend, "remote_network", None)  # the sandbox's child: the trusted side's network
        network = remote(config if config is not None else NetworkConfig()) if callable(remote) else None
        self.robots = RobotControllers(arena.n, controller, config, positions=arena.poses()[:, :2],
                                       sensors=sensors if sensors is not None else _arena_readings(arena),
                                       strict=strict, seal=self._seal, network=network)
        if getattr(arena.backend, "isolate_controllers", False):  # the sandbox's child always isolates (PipeRobots)
            isolate = True
        if isolate:
            self.robots.isolate(in_worker=self._seal_for_good)
        self.robots.on_event = arena.events.append
        self.network = self.robots.network
        self.config = self.robots.config
        arena.network = self.network  # `swarmdeck run --record` records its traffic (console/recording/arena_recording.py)
        attach = getattr(arena.backend, "attach_network", None)
        if callable(attach):  # robots behind a trust boundary report the traffic to the trusted side (sandbox child)
            attach(self.network)

    def _seal(self, who: str | None) -> None:
        self.arena._sealed_for = who

    def _seal_for_good(self, i: int) -> None:
        """In robot i's own process (isolated): the Arena refuses every look at the swarm for good."""
        self.arena._sealed_for = f"robot {i}'s controller"

    def close(self) -> None:
        """End the controllers' processes (``isolate``); the run's end does it too."""
        self.robots.close()

    @property
    def tick(self) -> int:
        """Ticks run so far."""
        return self.robots.tick

    @property
    def errors(self) -> Counter[str]:
        """Controller errors and refused messages by kind."""
        return self.robots.errors

    @property
    def events(self) -> deque[str]:
        """The most recent errors' messages."""
        return self.robots.events

    @property
    def states(self) -> list[dict[str, Any]]:
        """Each robot's ``view.state``."""
        return self.robots.states

    @property
    def last_commands(self) -> NDArray[np.float64]:
        """The last tick's commands ``(N, 2)`` m/s (zero for robots whose controller failed)."""
        return self.robots.last_commands

    def step(self) -> NDArray[np.float64]:
        """One tick: every controller, the messages, one arena step, the network at the new positions.

        Returns the new poses ``(N, 3)``.
        """
        arena = self.arena
        commands = self.robots.decide(arena.poses(), arena.time)
        arena.set_velocities(commands)
        new_poses = arena.step()
        self.network.step(new_poses[:, :2])
        return new_poses

    def traffic(self) -> NetworkTraffic:
        """The last tick's communication graph and the messages delivered over each link."""
        return self.network.traffic()

    def report(self) -> dict[str, Any]:
        """:meth:`RobotControllers.report`."""
        return self.robots.report()


def _arena_readings(arena: Arena) -> ReadingsSource | None:
    """``arena.sense().robot(i)`` when the arena has the sensing layer and sensors configured, else None."""
    sense = getattr(type(arena), "sense", None)
    if sense is None or getattr(arena, "sensors", None) is None:
        return None

    def readings(i: int) -> Any:
        current = sense(arena)
        return None if current is None else current.robot(i)

    return readings
