"""The GRITSBot's battery: one LiPo cell, drained by driving, recharged on the charging strips.

Paper §III-C ("Charging"): robots back onto magnetic charging strips in the arena walls.
State of charge ``q`` ∈ [0, 1] per robot; all functions take and return ``(N,)`` arrays,
never mutate their arguments and have no per-robot Python loop.

* Voltage: linear between ``empty_voltage`` (q = 0) and ``full_voltage`` (q = 1), and its
  inverse :func:`charge_from_voltage` (for robots that report only a voltage, REFERENCE.md §9
  ``batt_volt``).
* Drain (undocked): I = I_idle + k·(|ω_R| + |ω_L|) A, so dq = −I·dt / (3600·C).
* Charge (docked, constant current then constant voltage): I = I_cc while q < q_cv, then
  I = I_cc·(1 − q)/(1 − q_cv), so above q_cv the remaining gap closes exponentially with time
  constant τ = 3600·C·(1 − q_cv)/I_cc. :func:`recharge` integrates this exactly over any dt.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.checks import require_positive
from swarmdeck.core.kinematics import UnicycleParams, unicycle_to_wheels

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class BatteryParams:
    """A one-cell LiPo with a linear voltage-versus-charge curve and a CC-CV charger.

    Attributes:
        full_voltage, empty_voltage: V at 100 % and 0 % charge.
        capacity_ah: usable capacity C, Ah.
        idle_current: A drawn by the computer and radio whenever the robot is off the charger.
        motor_current_per_wheel_speed: A per rad/s of wheel speed, summed over both wheels.
        charge_current: I_cc, the charger's constant current, A (0.5 A = C/2 for 1 Ah).
        cv_start: q_cv ∈ (0, 1), state of charge where the charger switches to constant voltage
            and the current tapers.
    """

    full_voltage: float = 4.2
    empty_voltage: float = 3.3
    capacity_ah: float = 1.0
    idle_current: float = 0.25
    motor_current_per_wheel_speed: float = 0.02
    charge_current: float = 0.5
    cv_start: float = 0.8

    def __post_init__(self) -> None:
        if not (0 < self.empty_voltage < self.full_voltage):
            raise ValueError(f"BatteryParams needs 0 < empty_voltage < full_voltage, got {self.empty_voltage}, {self.full_voltage}")
        require_positive(self, ("capacity_ah", "charge_current"))
        require_positive(self, ("idle_current", "motor_current_per_wheel_speed"), allow_zero=True)
        if not (isinstance(self.cv_start, (int, float)) and 0.0 < self.cv_start < 1.0):
            raise ValueError(f"BatteryParams.cv_start must be in (0, 1), got {self.cv_start!r}")

    def voltage(self, charge: ArrayLike) -> FloatArray:
        """Terminal voltage for state of charge ``charge`` ∈ [0, 1], V (NaN stays NaN)."""
        c = np.clip(np.asarray(charge, dtype=float), 0.0, 1.0)
        return self.empty_voltage + (self.full_voltage - self.empty_voltage) * c


def charge_from_voltage(volts: ArrayLike, params: BatteryParams = BatteryParams()) -> FloatArray:
    """State of charge ``(N,)`` ∈ [0, 1] for terminal voltages ``(N,)`` V (inverse of ``params.voltage``;
    clipped; NaN, a robot that never reported, stays NaN)."""
    v = np.asarray(volts, dtype=float)
    return np.clip((v - params.empty_voltage) / (params.full_voltage - params.empty_voltage), 0.0, 1.0)


def drain_current(right: ArrayLike, left: ArrayLike, params: BatteryParams = BatteryParams()) -> FloatArray:
    """Current ``(N,)`` A drawn off the charger with wheel speeds ω_R, ω_L ``(N,)`` rad/s:
    I = I_idle + k·(|ω_R| + |ω_L|)."""
    return params.idle_current + params.motor_current_per_wheel_speed * (np.abs(np.asarray(right, dtype=float))
                                                                         + np.abs(np.asarray(left, dtype=float)))


def discharge(charge: ArrayLike, amp_seconds: ArrayLike, params: BatteryParams = BatteryParams()) -> FloatArray:
    """Charge ``(N,)`` after drawing ``amp_seconds`` ``(N,)`` A·s: q − A·s / (3600·C), clipped to [0, 1]."""
    q = np.asarray(charge, dtype=float)
    return np.clip(q - np.asarray(amp_seconds, dtype=float) / (3600.0 * params.capacity_ah), 0.0, 1.0)


def recharge(charge: ArrayLike, dt: float, params: BatteryParams = BatteryParams()) -> FloatArray:
    """Charge ``(N,)`` after ``dt`` s on the charger, integrated exactly (module docstring, CC-CV).

    Constant current up to q_cv (dq/dt = I_cc / (3600·C)), then 1 − q decays as exp(−t/τ).
    """
    q = np.clip(np.asarray(charge, dtype=float), 0.0, 1.0)
    dt = float(dt)
    if not dt >= 0:
        raise ValueError(f"recharge: dt must be >= 0 s, got {dt!r}")
    rate = params.charge_current / (3600.0 * params.capacity_ah)  # 1/s during constant current
    qcv = params.cv_start
    t_cc = np.clip((qcv - q) / rate, 0.0, dt)  # time spent in constant current within dt
    q_mid = np.where(q < qcv, q + rate * t_cc, q)
    tau = (1.0 - qcv) / rate
    gap = (1.0 - q_mid) * np.exp(-(dt - t_cc) / tau)
    return np.where(q < qcv, np.where(t_cc < dt, 1.0 - gap, q_mid), 1.0 - gap)


def battery_step(charge: ArrayLike, dt: float, v: ArrayLike, w: ArrayLike, docked: ArrayLike,
                 robot: UnicycleParams, params: BatteryParams = BatteryParams()) -> FloatArray:
    """Charge ``(N,)`` after one period of ``dt`` s: docked robots recharge, the others drain with
    the unicycle commands ``(v, ω)`` ``(N,)`` they drove (wheel map of ``robot``)."""
    right, left = unicycle_to_wheels(v, w, robot)
    drained = discharge(charge, drain_current(right, left, params) * dt, params)
    return np.where(np.asarray(docked, dtype=bool), recharge(charge, dt, params), drained)
