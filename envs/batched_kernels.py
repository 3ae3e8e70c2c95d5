"""The batched tick's arithmetic compiled: :mod:`swarmdeck.core.kinematics` term for term, for E·N robots in two calls.

:class:`swarmdeck.envs.batched_swarm.BatchedSwarm` runs the arena's pipeline on E·N robots a tick; at (E, N) =
(64, 10) its cost was numpy's per-call overhead (≈ 60 small array operations), not arithmetic. These kernels do
the same floating-point operations, in the same order, as the numpy functions they stand for
(:func:`~swarmdeck.core.kinematics.si_to_unicycle`, :func:`~swarmdeck.core.kinematics.limit_unicycle`,
:func:`~swarmdeck.core.kinematics.unicycle_to_si`, :func:`~swarmdeck.core.kinematics.unicycle_step` and the
pipeline's ``certify`` without a filter), one robot at a time: products and sums of two terms, no fused
multiply-add (numba compiles without fast-math), so the results are the same bits
(tests/envs/test_envs_batched_equal.py: swarm e equals an ``Arena`` bit for bit). Small calls without numba
imported take the numpy paths (:func:`use_compiled`). Every transcendental function
(cos, sin, arctan2, the power a³) stays with numpy, computed on the same array layouts as in
``core.kinematics``, so its bits are numpy's on every machine. Without numba the numpy functions run instead
(``batched_swarm``).

Units: c, s (M,) cos θ and sin θ; nominal (M, 2) m/s; v m/s, w rad/s; ℓ, r, L m; dt s.
"""
from __future__ import annotations

import numpy as np

from swarmdeck.core.compiled import AVAILABLE, imported, jit

__all__ = ["COMPILED_FROM", "certify_off", "step_prepare", "step_move", "task_observations", "use_compiled"]

#: robots (E·N in one call) from which the batched environment's compiled paths run when numba is not imported yet:
#: a deployed policy's observations (:mod:`swarmdeck.envs.deploy`: one swarm of a few robots, in the sandbox) never
#: import numba or compile a kernel there (seconds of CPU on the first tick, over the script's per-tick budget)
COMPILED_FROM = 64


def use_compiled(robots: int) -> bool:
    """Whether a call on ``robots`` robots takes the compiled path: numba installed, and the call large enough or
    numba already imported (then the kernels are the faster way to the same bits)."""
    return AVAILABLE and (robots >= COMPILED_FROM or imported())

SMALL_TURN = 1e-6  # rad: core.kinematics.unicycle_step's switch to the series of sin(a)/a, (1 − cos a)/a


@jit
def certify_off(c, s, nominal, ell, axle, two_r, max_wheel, threshold, v_out, w_out, invalid_out,
                last_out):  # pragma: no cover - compiled
    """``devices.pipeline.certify(poses, nominal, robot)`` without a filter: rows with NaN/inf stop (invalid_out,
    last_out = the nominal with those rows zero), ``si_to_unicycle`` then ``limit_unicycle`` (one scale per robot
    when a wheel exceeds ``threshold`` = max_wheel·(1 + 1e-12)); writes v_out, w_out."""
    for k in range(c.shape[0]):
        u0 = nominal[k, 0]
        u1 = nominal[k, 1]
        bad = not (np.isfinite(u0) and np.isfinite(u1))
        if bad:
            u0 = 0.0
            u1 = 0.0
        invalid_out[k] = bad
        last_out[k, 0] = u0
        last_out[k, 1] = u1
        ck = c[k]
        sk = s[k]
        v = ck * u0 + sk * u1
        w = (-sk * u0 + ck * u1) / ell
        right = (2.0 * v + w * axle) / two_r
        left = (2.0 * v - w * axle) / two_r
        ar = abs(right)
        al = abs(left)
        peak = ar if (ar >= al or ar != ar) else al  # np.maximum: NaN propagates
        scale = max_wheel / peak if peak > threshold else 1.0
        v_out[k] = v * scale
        w_out[k] = w * scale


@jit
def step_prepare(c, s, v, w, last, ell, dt, change_out, a_out, small_out, a_safe_out):  # pragma: no cover - compiled
    """The command's look-ahead velocity ``unicycle_to_si`` minus ``last`` (M, 2), its norm into change_out (m/s),
    and ``unicycle_step``'s heading change a = w·dt, small = |a| < SMALL_TURN, a_safe (1 where small)."""
    for k in range(c.shape[0]):
        ck = c[k]
        sk = s[k]
        vk = v[k]
        wk = w[k]
        d0 = (ck * vk - ell * sk * wk) - last[k, 0]
        d1 = (sk * vk + ell * ck * wk) - last[k, 1]
        change_out[k] = np.sqrt(d0 * d0 + d1 * d1)
        a = wk * dt
        small = abs(a) < SMALL_TURN
        a_out[k] = a
        small_out[k] = small
        a_safe_out[k] = 1.0 if small else a


@jit
def step_move(poses, c, s, v, a, small, a_safe, sin_a, cos_a, cube, dt, out, heading_out):  # pragma: no cover - compiled
    """``unicycle_step`` without the final wrap: x, y into out[:, :2] and θ + a into heading_out (numpy wraps it).
    sin_a, cos_a: np.sin/np.cos of a_safe; cube: a**3 (read only where small)."""
    for k in range(c.shape[0]):
        ak = a[k]
        if small[k]:
            f = 1.0 - ak * ak / 6.0
            g = ak / 2.0 - cube[k] / 24.0
        else:
            f = sin_a[k] / a_safe[k]
            g = (1.0 - cos_a[k]) / a_safe[k]
        d = v[k] * dt
        ck = c[k]
        sk = s[k]
        out[k, 0] = poses[k, 0] + d * (f * ck - g * sk)
        out[k, 1] = poses[k, 1] + d * (f * sk + g * ck)
        heading_out[k] = poses[k, 2] + ak


@jit
def task_observations(poses, cos_t, sin_t, points, idx, n, k, x0, x1, y0, y1, slots, out):  # pragma: no cover
    """``envs.scenarios.task_observations`` (the layout of ``envs.observations``) into out (E·N, D) float32:
    own [x, y, cos θ, sin θ], p_j − p_i of the neighbours idx (E·N, k') within the swarm (zeros beyond k'),
    the four wall distances of the look-ahead point, then ``slots[i] − p_i`` when slots has rows (formation).
    Each entry is the float64 expression rounded once to float32, as numpy's ``astype``."""
    kk = idx.shape[1]
    for r in range(poses.shape[0]):
        base = (r // n) * n
        px = points[r, 0]
        py = points[r, 1]
        out[r, 0] = poses[r, 0]
        out[r, 1] = poses[r, 1]
        out[r, 2] = cos_t[r]
        out[r, 3] = sin_t[r]
        for h in range(k):
            if h < kk:
                j = base + idx[r, h]
                out[r, 4 + 2 * h] = points[j, 0] - px
                out[r, 5 + 2 * h] = points[j, 1] - py
            else:
                out[r, 4 + 2 * h] = 0.0
                out[r, 5 + 2 * h] = 0.0
        c = 4 + 2 * k
        out[r, c] = px - x0
        out[r, c + 1] = x1 - px
        out[r, c + 2] = py - y0
        out[r, c + 3] = y1 - py
        if slots.shape[0] > 0:
            out[r, c + 4] = slots[r - base, 0] - px
            out[r, c + 5] = slots[r - base, 1] - py
