"""Unicycle barrier: the single-integrator QP on the look-ahead points, within wheel limits.

For poses (x, y, θ) the controlled point is p = (x + ℓ cos θ, y + ℓ sin θ)
(REFERENCE.md §1, Olfati-Saber; the map and its inverse are in
:mod:`swarmdeck.core.kinematics`). The barrier rows of :mod:`constraints` act on
p with the filter's D_s (the default 0.17 m = Ø 0.11 + 2ℓ keeps the bodies
apart: each centre lies within ℓ of its point). Instead of a speed disc, each
robot gets the four wheel-limit rows |ω_R|, |ω_L| ≤ ω_max with
ω_R,L = (v ± Lω/2)/r — exactly the commands the robot can execute, so no
saturation is needed afterwards and the certificate holds for what is driven.
"""
from __future__ import annotations

import dataclasses
import time

import numpy as np
from numpy.typing import ArrayLike

from swarmdeck.core.kinematics import (
    UnicycleParams,
    lookahead_points,
    si_to_unicycle,
    unicycle_to_si,
    unicycle_to_wheels,
)

from .config import BarrierConfig
from .constraints import LIMIT, Rows
from .diagnostics import BarrierDiagnostics
from .filter import InputError, SafetyFilter, as_points, as_robot_bounds, robot_count


def wheel_limit_rows(poses: np.ndarray, params: UnicycleParams, n_obs: int = 0) -> Rows:
    """Rows ±ω_R ≤ ω_max, ±ω_L ≤ ω_max as linear rows on the point velocity u_i (normalised)."""
    n = poses.shape[0]
    c, s = np.cos(poses[:, 2]), np.sin(poses[:, 2])
    k = params.axle_length / (2 * params.lookahead)
    r = params.wheel_radius
    g = np.empty((n, 4, 2))  # per robot: right, −right, left, −left wheel's row
    g[:, 0, 0] = c - k * s
    g[:, 0, 1] = s + k * c
    g[:, 2, 0] = c + k * s
    g[:, 2, 1] = s - k * c
    g[:, 0::2] /= r
    np.negative(g[:, 0::2], out=g[:, 1::2])
    flat = g.reshape(-1, 2)  # (4N, 2)
    norm = np.sqrt(1 + k * k) / r
    row = np.arange(4 * n, dtype=np.int64)
    i = row // 4
    key = n * n + 4 * n + n * n_obs + row  # 4i + side
    return Rows(i, np.full_like(i, -1), flat / norm, np.zeros_like(flat), np.full(4 * n, params.max_wheel_speed / norm),
                np.full(4 * n, np.inf), np.full(4 * n, LIMIT, dtype=np.int8), key)


def max_point_speed(params: UnicycleParams) -> float:
    """Largest look-ahead point speed reachable within the wheel limits, m/s."""
    v = params.max_linear_speed
    return max(v, params.lookahead * 2 * v / params.axle_length)


class UnicycleSafetyFilter:
    """Barrier filter for unicycle robots: poses and (v, ω) in, safe (v, ω) out.

    ``filter(poses (N, 3), v (N,), w (N,), obstacles=None) -> (v_safe, w_safe, diag)``;
    the safe commands keep every wheel within ±max_wheel_speed. The config's
    max_speed is replaced by the fastest look-ahead speed the wheels allow
    (it sets the neighbour radius). A safe nominal is returned bit-for-bit.
    """

    def __init__(self, config: BarrierConfig | None = None, params: UnicycleParams | None = None, *,
                 robots: int | None = None) -> None:
        """``robots``: the robot count the caller will filter, when known (:class:`SafetyFilter`)."""
        self.params = UnicycleParams() if params is None else params
        base = BarrierConfig() if config is None else config
        self.config = dataclasses.replace(base, max_speed=max_point_speed(self.params))
        self._si = SafetyFilter(self.config, robots=robots)

    def reset(self) -> None:
        """Forget the warm start."""
        self._si.reset()

    def filter(self, poses: ArrayLike, v: ArrayLike, w: ArrayLike, obstacles: ArrayLike | None = None, *,
               robot_bounds: ArrayLike | None = None) -> tuple[np.ndarray, np.ndarray, BarrierDiagnostics]:
        """Safe (v (N,) m/s, ω (N,) rad/s) and diagnostics (intervention in point m/s); ``robot_bounds``
        (N, 4) m: each robot's own wall rectangle (its region of a shared floor) instead of the config's."""
        t0 = time.perf_counter()
        try:
            X = np.asarray(poses, dtype=float)
            if X.ndim != 2 or X.shape[1] != 3:
                raise InputError(f"poses must have shape (N, 3), got {X.shape}")
            n = X.shape[0]
            V = np.asarray(v, dtype=float)
            Wc = np.asarray(w, dtype=float)
            if V.shape != (n,) or Wc.shape != (n,):
                raise InputError(f"v and w must have shape ({n},), got {V.shape} and {Wc.shape}")
            if not (np.isfinite(X).all() and np.isfinite(V).all() and np.isfinite(Wc).all()):
                raise InputError("poses, v or w contain NaN or inf")
            O = None if obstacles is None else as_points(obstacles, "obstacles")
            B = None if robot_bounds is None else as_robot_bounds(robot_bounds, n)
        except (InputError, TypeError, ValueError) as exc:
            n = robot_count(v, poses)  # the poses' row count first
            _, diag = self._si.fail_stop(n, np.zeros((n, 2)), f"invalid input: {exc}", t0)
            return np.zeros(n), np.zeros(n), diag
        ell = self.params.lookahead
        P = lookahead_points(X, ell)
        U = unicycle_to_si(X, V, Wc, ell)
        extra = wheel_limit_rows(X, self.params, 0 if O is None else O.shape[0])
        u, diag = self._si.solve(P, U, O, extra, None, t0, robot_bounds=B)
        if not diag.ok:
            return np.zeros(n), np.zeros(n), diag
        if diag.nominal_was_safe:
            return V.copy(), Wc.copy(), diag
        vs, ws = si_to_unicycle(X, u, ell)
        # the rows hold to 1e-8 m/s; remove that rounding so the wheels never exceed the limit
        wr, wl = unicycle_to_wheels(vs, ws, self.params)
        peak = np.maximum(np.abs(wr), np.abs(wl))
        scale = np.minimum(1.0, self.params.max_wheel_speed / np.maximum(peak, 1e-300))
        # robots the QP left alone get their own command back bit for bit, not its round trip
        untouched = np.all(u == U, axis=1)
        return np.where(untouched, V, vs * scale), np.where(untouched, Wc, ws * scale), diag
