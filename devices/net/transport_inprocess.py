"""The default transport: the simulated arena in this process (no broker, no sockets).

Each :meth:`InProcessTransport.send` is one control tick: robots named get
their command, robots not named get zero (a robot nobody commands stands
still, as after the firmware's 500 ms brake), and the
:class:`~swarmdeck.devices.simulator.SimulatedArena` steps once on its virtual
clock — so a run is exactly reproducible. Battery voltages follow the same
model as the networked fleet (:mod:`swarmdeck.devices.battery`).
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.devices.battery import BatteryParams, battery_step
from swarmdeck.devices.net.transport import (
    LINK_OK,
    Counters,
    PoseSample,
    RobotStatusTable,
    TransportStatus,
    check_command,
)
from swarmdeck.devices.simulator import SimulatedArena


class InProcessTransport:
    """Robots of a :class:`SimulatedArena` behind the transport interface.

    Args:
        arena: the simulation (stepped once per :meth:`send`).
        battery: battery model for the status reports.

    The clock of this transport is the arena's virtual clock: use
    ``clock=lambda: transport.time`` for a streamer on top of it.
    """

    def __init__(self, arena: SimulatedArena, battery: BatteryParams = BatteryParams()) -> None:
        self.arena = arena
        self.battery = battery
        self.counters = Counters()
        n = arena.n
        self._ids = np.arange(n, dtype=np.intp)
        self._charge = np.ones(n)
        self._last_cmd = np.full(n, -np.inf)
        self._closed = False

    @property
    def time(self) -> float:
        return self.arena.time

    def send(self, ids: ArrayLike, v: ArrayLike, w: ArrayLike, leds: ArrayLike | None = None) -> bool:
        """Apply the commands for one period (``arena.config.dt``) and step the simulation."""
        cmd = check_command(ids, v, w, leds)
        ok = not cmd.problems
        for p in cmd.problems:
            self.counters.add("bad_command", p)
        n = self.arena.n
        known = cmd.ids < n
        if not known.all():
            self.counters.add("unknown_id", f"command for unknown robot id(s) {cmd.ids[~known].tolist()} ignored "
                              f"(this arena has ids 0..{n - 1})")
            ok = False
        if self._closed:
            self.counters.add("undeliverable", "transport closed", n=len(cmd.ids))
            return False
        v_full = np.zeros(n)
        w_full = np.zeros(n)
        sel = cmd.ids[known]
        v_full[sel] = cmd.v[known]
        w_full[sel] = cmd.w[known]
        t0 = self.arena.time
        self.arena.step(v_full, w_full)
        dt = self.arena.time - t0
        av, aw = self.arena.applied
        self._charge = battery_step(self._charge, dt, av, aw, np.zeros(n, dtype=bool), self.arena.params, self.battery)
        self._last_cmd[sel] = self.arena.time
        self.counters.add("commands_sent", n=len(sel))
        return ok

    def latest_poses(self) -> PoseSample:
        """Exact poses of every robot, stamped with the arena's time."""
        n = self.arena.n
        return PoseSample(self._ids.copy(), self.arena.poses, np.full(n, self.arena.time))

    def status(self) -> TransportStatus:
        n = self.arena.n
        table = RobotStatusTable(
            self._ids.copy(), self.battery.voltage(self._charge), np.zeros(n, dtype=bool),
            self.arena.time - self._last_cmd, np.zeros(n), tuple([LINK_OK] * n),
        )
        state = "closed" if self._closed else "in-process simulation"
        return TransportStatus(not self._closed, state, table, self.counters.snapshot(), self.counters.last_error)

    def robots(self) -> NDArray[np.intp]:
        return self._ids.copy()

    def excluded(self) -> NDArray[np.intp]:
        return np.empty(0, dtype=np.intp)

    def close(self) -> None:
        self._closed = True
