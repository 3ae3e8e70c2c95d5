"""The pose a recording predicts for the next frame: the unicycle step, in portable arithmetic.

Frame format 3 (:mod:`~swarmdeck.console.recording.codec`) stores a frame's exact poses as the
XOR of their bits with :func:`predict_poses` of the previous frame — its poses moved by its
applied command (v, ω) over its period ``dt``: the step the simulator takes
(:func:`swarmdeck.core.kinematics.unicycle_step`, the exact arc of constant (v, ω); the
same formula, sin(a)/a and (1 − cos a)/a by their series for |a| < 1e-6), so a simulated
robot's residual is zero or a few low bits, a tracked robot's only its measurement noise.

The writer and every reader, on any machine and any numpy, must compute the *same bits*, or
the poses read back would be wrong. numpy's ``sin``/``cos``/``arctan2`` do not promise that
(they dispatch to SIMD kernels chosen by the CPU, and change between releases), so this module
uses only IEEE-754 operations that are correctly rounded everywhere — elementwise ``+ − × /``,
``rint``, comparisons — on float64: sin and cos are fdlibm's kernels (FreeBSD ``k_sin.c``,
``k_cos.c``, error < 1 ulp) after a three-part Cody–Waite reduction by π/2 (``e_rem_pio2.c``),
and the heading is wrapped into (−π, π] by adding or subtracting 2π (the simulator's
``arctan2(sin, cos)`` wrap differs from it by an ulp or so: low bits in the residual). Where an
input is not finite, or a heading is beyond ±2²⁰·π/2 (outside the reduction's range), the
prediction is the previous pose unchanged. What the prediction is does not affect
exactness — the residual carries the difference — only how well the residual compresses.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

# fdlibm (FreeBSD msun) constants, bit-exact as decimal literals.
_S1, _S2, _S3 = -1.66666666666666324348e-01, 8.33333333332248946124e-03, -1.98412698298579493134e-04
_S4, _S5, _S6 = 2.75573137070700676789e-06, -2.50507602534068634195e-08, 1.58969099521155010221e-10
_C1, _C2, _C3 = 4.16666666666666019037e-02, -1.38888888888741095749e-03, 2.48015872894767294178e-05
_C4, _C5, _C6 = -2.75573143513906633035e-07, 2.08757232129817482790e-09, -1.13596475577881948265e-11
_INVPIO2 = 6.36619772367581382433e-01
_PIO2_1, _PIO2_1T = 1.57079632673412561417e+00, 6.07710050650619224932e-11
_PIO2_2, _PIO2_2T = 6.07710050630396597660e-11, 2.02226624879595063154e-21
_PIO2_3, _PIO2_3T = 2.02226624871116645580e-21, 8.47842766036889956997e-32
_PIO4 = 7.85398163397448278999e-01  # fdlibm reduces above |x| > 0x3fe921fb...: π/4 rounded down
_MAX_REDUCE = 2.0**20 * 1.57079632679489655800e+00  # fdlibm's "medium" range: fn fits 20 bits
_PI = 3.14159265358979311600e+00
_TWO_PI = 6.28318530717958623200e+00


def _k_sin(x: FloatArray, y: FloatArray) -> FloatArray:
    """sin(x + y), |x| ≤ π/4, y the tail of x (FreeBSD k_sin.c, iy = 1)."""
    z = x * x
    w = z * z
    r = _S2 + z * (_S3 + z * _S4) + z * w * (_S5 + z * _S6)
    v = z * x
    return x - ((z * (0.5 * y - v * r) - y) - v * _S1)


def _k_sin0(x: FloatArray) -> FloatArray:
    """sin(x), |x| ≤ π/4, no tail (FreeBSD k_sin.c, iy = 0)."""
    z = x * x
    w = z * z
    r = _S2 + z * (_S3 + z * _S4) + z * w * (_S5 + z * _S6)
    return x + (z * x) * (_S1 + z * r)


def _k_cos(x: FloatArray, y: FloatArray) -> FloatArray:
    """cos(x + y), |x| ≤ π/4, y the tail of x (FreeBSD k_cos.c)."""
    z = x * x
    w = z * z
    r = z * (_C1 + z * (_C2 + z * _C3)) + w * w * (_C4 + z * (_C5 + z * _C6))
    hz = 0.5 * z
    w = 1.0 - hz
    return w + (((1.0 - w) - hz) + (z * r - x * y))


def sin_cos(x: FloatArray) -> tuple[FloatArray, FloatArray]:
    """(sin x, cos x) elementwise for |x| ≤ 2²⁰·π/2 from IEEE +, −, ×, rint only (same bits on every
    machine; error < 1 ulp, fdlibm). Outside that range, and for non-finite x, the result is NaN."""
    x = np.asarray(x, dtype=np.float64)
    ok = np.abs(x) <= _MAX_REDUCE  # False for NaN and ±inf
    xs = np.where(ok, x, 0.0)
    fn = np.rint(xs * _INVPIO2)
    # three-part Cody–Waite reduction x − fn·π/2 = y0 + y1 (e_rem_pio2.c, every round always taken)
    r = xs - fn * _PIO2_1
    w = fn * _PIO2_1T
    t = r
    w = fn * _PIO2_2
    r = t - w
    w = fn * _PIO2_2T - ((t - r) - w)
    t = r
    w = fn * _PIO2_3
    r = t - w
    w = fn * _PIO2_3T - ((t - r) - w)
    y0 = r - w
    y1 = (r - y0) - w
    small = np.abs(xs) <= _PIO4  # no reduction (as fdlibm: the kernels on x itself, no tail)
    y0 = np.where(small, xs, y0)
    y1 = np.where(small, 0.0, y1)
    q = np.where(small, 0, fn.astype(np.int64) & 3)
    ks = np.where(small, _k_sin0(y0), _k_sin(y0, y1))
    kc = _k_cos(y0, y1)
    sin = np.select([q == 0, q == 1, q == 2], [ks, kc, -ks], -kc)
    cos = np.select([q == 0, q == 1, q == 2], [kc, -ks, -kc], ks)
    nan = np.full_like(xs, np.nan)
    return np.where(ok, sin, nan), np.where(ok, cos, nan)


def predict_poses(poses: FloatArray, v: FloatArray, w: FloatArray, dt: float) -> FloatArray:
    """Poses ``(N, 3)`` [x, y, θ] (m, rad) after ``dt`` s of constant (v, ω) (``(N,)`` m/s, rad/s)
    from ``poses``: x' = x + v·dt·(f cos θ − g sin θ), y' = y + v·dt·(f sin θ + g cos θ),
    θ' = θ + a wrapped into (−π, π], with a = ω·dt, f = sin(a)/a, g = (1 − cos a)/a (their
    series 1 − a²/6 and a/2 − a³/24 for |a| < 1e-6) — the simulator's unicycle step
    (REFERENCE.md §1) in machine-independent arithmetic (module docstring). Rows with a
    non-finite result keep the input pose. Returns a new array."""
    poses = np.asarray(poses, dtype=np.float64).reshape(-1, 3)
    v = np.asarray(v, dtype=np.float64).reshape(-1)
    w = np.asarray(w, dtype=np.float64).reshape(-1)
    dt = float(dt)
    theta = poses[:, 2]
    with np.errstate(all="ignore"):
        a = w * dt
        small = np.abs(a) < 1e-6
        a_safe = np.where(small, 1.0, a)
        sa, ca = sin_cos(a_safe)
        f = np.where(small, 1.0 - a * a / 6.0, sa / a_safe)
        g = np.where(small, a / 2.0 - a * a * a / 24.0, (1.0 - ca) / a_safe)
        d = v * dt
        s, c = sin_cos(theta)
        out = np.empty_like(poses)
        out[:, 0] = poses[:, 0] + d * (f * c - g * s)
        out[:, 1] = poses[:, 1] + d * (f * s + g * c)
        t = theta + a
        t = np.where(t > _PI, t - _TWO_PI, np.where(t <= -_PI, t + _TWO_PI, t))
        out[:, 2] = t
    keep = ~np.isfinite(out).all(axis=1)
    out[keep] = poses[keep]
    return out


__all__ = ["predict_poses", "sin_cos"]
