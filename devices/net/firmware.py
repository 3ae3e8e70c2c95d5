"""The GRITSBot X firmware as a model: newest command wins, 500 ms brake, battery drain.

Pure state on explicit times (no clock, no sockets), so tests drive it with a
virtual clock and the networked fleet (:mod:`swarmdeck.devices.net.fleet`)
with the monotonic clock. REFERENCE.md §9 / notes/robotarium.md §4.3:

* the robot keeps only the newest command; a command takes effect when it is
  received and lasts until a newer one arrives;
* with no command for ``command_timeout`` (500 ms, ``communicationCheck(500)``)
  the robot brakes to zero — modelled exactly: a command received at t_c moves
  the robot on [t_c, t_c + 0.5 s] and not a moment longer, whatever the loop jitter;
* wheel limits by one uniform scale per robot
  (:func:`~swarmdeck.core.kinematics.limit_unicycle`), exact unicycle arcs
  (:func:`~swarmdeck.devices.gritsbot.unicycle_step`);
* the battery of :mod:`swarmdeck.devices.fleet.battery` (voltage linear in the charge drawn,
  I = I_idle + k·(|ω_R| + |ω_L|) while driving, I_idle otherwise); a robot docked on a slot of
  the charging strips (``chargers``, :meth:`ChargerLayout.docked_slot`) charges instead (CC-CV,
  :func:`~swarmdeck.devices.fleet.battery.recharge`) and reports ``charge_status`` true.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.checks import in_range, require_positive
from swarmdeck.core.kinematics import GritsBotParams, limit_unicycle, unicycle_to_wheels
from swarmdeck.devices.fleet.battery import BatteryParams, discharge, recharge
from swarmdeck.devices.fleet.chargers import ChargerLayout
from swarmdeck.devices.gritsbot import unicycle_step

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class FirmwareParams:
    """Timing of the simulated robot firmware (notes/robotarium.md §4.3).

    Attributes:
        command_timeout: brake after this long without a command, s (firmware: 0.5).
        loop_period: firmware loop, s (GRITSBot X: 0.016).
        status_period: status report interval, s (firmware: 1.0).
        pose_period: ground-truth pose publication interval, s (tracker: 30 fps).
        pose_decimals: rounding of published poses (camera tracker 2, Vicon 3).
    """

    command_timeout: float = 0.5
    loop_period: float = 0.016
    status_period: float = 1.0
    pose_period: float = 0.033
    pose_decimals: int = 3

    def __post_init__(self) -> None:
        require_positive(self, ("command_timeout", "loop_period", "status_period", "pose_period"), "seconds")
        if not in_range(self.pose_decimals, 0, 6, integer=True):
            raise ValueError(f"FirmwareParams.pose_decimals must be 0..6, got {self.pose_decimals!r}")


class FleetState:
    """N simulated GRITSBots running the firmware model.

    Args:
        ids: ``(N,)`` distinct non-negative robot ids.
        poses: ``(N, 3)`` initial poses.
        t0: start time on the caller's clock, s.
        firmware, battery, params: models.
        charge: initial state of charge ``(N,)`` or scalar in [0, 1].
        chargers: the arena's charging strips (None: no chargers, robots only drain).
    """

    def __init__(
        self,
        ids: ArrayLike,
        poses: ArrayLike,
        t0: float = 0.0,
        *,
        firmware: FirmwareParams = FirmwareParams(),
        battery: BatteryParams = BatteryParams(),
        params: GritsBotParams = GritsBotParams(),
        charge: ArrayLike = 1.0,
        chargers: ChargerLayout | None = None,
    ) -> None:
        self.ids = np.asarray(ids, dtype=np.intp).reshape(-1).copy()
        n = len(self.ids)
        if n == 0 or np.any(self.ids < 0) or len(np.unique(self.ids)) != n:
            raise ValueError(f"ids must be distinct non-negative integers, got {self.ids.tolist()}")
        p = np.asarray(poses, dtype=float)
        if p.shape != (n, 3) or not np.all(np.isfinite(p)):
            raise ValueError(f"poses must be a finite ({n}, 3) array, got shape {p.shape}")
        self.firmware, self.battery, self.params = firmware, battery, params
        self.t = float(t0)
        self.poses = p.copy()
        self.charge = np.broadcast_to(np.asarray(charge, dtype=float), (n,)).copy()
        if not np.all((self.charge >= 0.0) & (self.charge <= 1.0)):
            raise ValueError(f"charge must be in [0, 1], got {self.charge.tolist()}")
        self.chargers = chargers
        self.docked = self._docked()
        self._index = {int(i): k for k, i in enumerate(self.ids)}
        # command in force: values, receive time (−inf: never)
        self.cur_v = np.zeros(n)
        self.cur_w = np.zeros(n)
        self.cur_t = np.full(n, -np.inf)
        # newest command received since the last advance
        self.pend_v = np.zeros(n)
        self.pend_w = np.zeros(n)
        self.pend_t = np.full(n, -np.inf)
        self.has_pend = np.zeros(n, dtype=bool)
        self.leds = np.zeros((n, 2, 3), dtype=np.uint8)
        self.commands_received = np.zeros(n, dtype=np.int64)
        self.timeouts = np.zeros(n, dtype=np.int64)  # times the 500 ms brake engaged on a moving robot
        self.saturated = np.zeros(n, dtype=np.int64)

    @property
    def n(self) -> int:
        return len(self.ids)

    def index_of(self, robot_id: int) -> int | None:
        """Row of ``robot_id``, or None when this fleet has no such robot."""
        return self._index.get(int(robot_id))

    def receive(self, rows: ArrayLike, v: ArrayLike, w: ArrayLike, t: ArrayLike,
                leds: NDArray[np.uint8] | None = None) -> None:
        """Commands ``(K,)`` for rows ``rows`` received at times ``t`` (keeps only the newest per robot).

        Commands stamped before the one already pending are ignored (out of order).
        """
        rows = np.asarray(rows, dtype=np.intp).reshape(-1)
        t = np.broadcast_to(np.asarray(t, dtype=float), rows.shape)
        v, w, sat = limit_unicycle(np.asarray(v, dtype=float).reshape(-1), np.asarray(w, dtype=float).reshape(-1), self.params)
        newer = t >= np.maximum(self.pend_t[rows], self.cur_t[rows])
        r = rows[newer]
        self.pend_v[r], self.pend_w[r], self.pend_t[r] = v[newer], w[newer], t[newer]
        self.has_pend[r] = True
        np.add.at(self.commands_received, rows, 1)
        np.add.at(self.saturated, rows[sat], 1)
        if leds is not None:
            self.leds[r] = np.asarray(leds, dtype=np.uint8)[newer]

    def advance(self, t_now: float) -> FloatArray:
        """Integrate every robot from :attr:`t` to ``t_now`` and return the new poses (a copy).

        The command in force applies until the newest pending one was received
        (or its own 500 ms deadline, whichever is first); the pending one applies
        from its receive time until ``t_now`` or its deadline.
        """
        t0 = self.t
        if not t_now > t0:
            return self.poses.copy()
        timeout = self.firmware.command_timeout
        split = np.where(self.has_pend, np.clip(self.pend_t, t0, t_now), t_now)
        live1 = np.clip(self.cur_t + timeout - t0, 0.0, split - t0)
        live2 = np.where(self.has_pend, np.clip(self.pend_t + timeout - split, 0.0, t_now - split), 0.0)
        # robots that brake in this interval: the segment in force ends by its deadline while moving
        moving1 = (self.cur_v != 0) | (self.cur_w != 0)
        moving2 = (self.pend_v != 0) | (self.pend_w != 0)
        braked = (moving1 & ~self.has_pend & (self.cur_t + timeout > t0) & (self.cur_t + timeout <= t_now)) | (
            moving2 & self.has_pend & (self.pend_t + timeout <= t_now)
        )
        self.timeouts += braked
        # Integrating (v, ω) for τ s equals integrating (v τ, ω τ) for 1 s.
        p = unicycle_step(self.poses, self.cur_v * live1, self.cur_w * live1, 1.0)
        p = unicycle_step(p, self.pend_v * live2, self.pend_w * live2, 1.0)
        self.poses = p
        # battery
        r1, l1 = unicycle_to_wheels(self.cur_v, self.cur_w, self.params)
        r2, l2 = unicycle_to_wheels(self.pend_v, self.pend_w, self.params)
        b = self.battery
        amp_s = b.idle_current * (t_now - t0) + b.motor_current_per_wheel_speed * (
            (np.abs(r1) + np.abs(l1)) * live1 + (np.abs(r2) + np.abs(l2)) * live2
        )
        # on a charger for the whole interval when docked at both ends (a robot driving off stops charging)
        docked_before = self.docked
        self.docked = self._docked()
        on_strip = docked_before & self.docked
        self.charge = np.where(on_strip, recharge(self.charge, t_now - t0, b), discharge(self.charge, amp_s, b))
        # the pending command is now in force
        h = self.has_pend
        self.cur_v = np.where(h, self.pend_v, self.cur_v)
        self.cur_w = np.where(h, self.pend_w, self.cur_w)
        self.cur_t = np.where(h, self.pend_t, self.cur_t)
        self.has_pend = np.zeros(self.n, dtype=bool)
        self.t = float(t_now)
        return self.poses.copy()

    # ---------------------------------------------------------------- reports
    def applied(self) -> tuple[FloatArray, FloatArray]:
        """``(v, ω)`` the wheels are following at :attr:`t` (zero once the 500 ms brake engaged)."""
        alive = self.t < self.cur_t + self.firmware.command_timeout
        return np.where(alive, self.cur_v, 0.0), np.where(alive, self.cur_w, 0.0)

    def command_age(self) -> FloatArray:
        """``(N,)`` s since the newest command was received (inf: never)."""
        return self.t - np.maximum(self.cur_t, np.where(self.has_pend, self.pend_t, -np.inf))

    def battery_voltage(self) -> FloatArray:
        return self.battery.voltage(self.charge)

    def charging(self) -> NDArray[np.bool_]:
        """``(N,)`` robots on a charger slot (``charge_status`` on the wire)."""
        return self.docked.copy()

    def _docked(self) -> NDArray[np.bool_]:
        if self.chargers is None:
            return np.zeros(self.n, dtype=bool)
        return self.chargers.docked_slot(self.poses) >= 0
