"""Per-source calibration: normalised surface coordinates → arena metres.

Input coordinates are TUIO-normalised: ``(u, v)`` in 0..1, origin at the
surface's top-left, v pointing *down* (REFERENCE.md §6). The map is affine::

    a = (u - 1/2, 1/2 - v)                  # centred, y up, unit-square units
    a = F a                                 # F = diag(±1, ±1) from flip_x / flip_y
    a = R(rotation) a                       # CCW rotation about the surface centre
    p = diag(scale_x W, scale_y H) a + c + offset

with ``W, H`` the arena width and height, ``c`` the arena centre (from
``bounds``). The default (no flips, no rotation, scale 1, offset 0) maps the
whole surface onto the whole arena. Velocities use the linear part only.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds, check_bounds
from swarmdeck.core.config import check_keys, field_names


@dataclass(frozen=True)
class Calibration:
    """Affine map from a source's normalised surface to the arena.

    Attributes:
        flip_x, flip_y: mirror the surface's horizontal / vertical axis.
        rotation: rad, counter-clockwise, applied after the flips.
        scale: (sx, sy) fraction of the arena width/height the surface covers.
        offset: (m, m) shift of the surface centre from the arena centre.
        bounds: arena ``(x_min, x_max, y_min, y_max)`` in metres.
    """

    flip_x: bool = False
    flip_y: bool = False
    rotation: float = 0.0
    scale: tuple[float, float] = (1.0, 1.0)
    offset: tuple[float, float] = (0.0, 0.0)
    bounds: Bounds = DEFAULT_BOUNDS

    def __post_init__(self) -> None:
        check_bounds(self.bounds, "calibration bounds")
        vals = (self.rotation, *self.scale, *self.offset)
        if len(self.scale) != 2 or len(self.offset) != 2 or not all(map(math.isfinite, vals)):
            raise ValueError(f"calibration scale and offset must be pairs of finite numbers, got scale={self.scale} offset={self.offset}")
        if self.scale[0] == 0 or self.scale[1] == 0:
            raise ValueError(f"calibration scale must be non-zero, got {self.scale}")

    def matrix(self) -> tuple[np.ndarray, np.ndarray]:
        """``(A (2,2), b (2,))`` with ``p = A @ (u, v) + b``; velocities map by ``A``."""
        b = Bounds.of(self.bounds)
        down = np.array([[1.0, 0.0], [0.0, -1.0]])  # (u, v) y-down -> y-up
        flips = np.diag([-1.0 if self.flip_x else 1.0, -1.0 if self.flip_y else 1.0])
        c, s = math.cos(self.rotation), math.sin(self.rotation)
        rot = np.array([[c, -s], [s, c]])
        sc = np.diag([self.scale[0] * b.width, self.scale[1] * b.height])
        a = sc @ rot @ flips @ down
        centre = np.array([b.centre[0] + self.offset[0], b.centre[1] + self.offset[1]])
        b = centre - a @ np.array([0.5, 0.5])
        return a, b

    def area_scale(self) -> float:
        """m² of arena per unit² of normalised surface (``|det A|``)."""
        a, _ = self.matrix()
        return float(abs(np.linalg.det(a)))

    def to_arena(self, uv: np.ndarray) -> np.ndarray:
        """(M, 2) normalised surface points → (M, 2) arena metres (new array)."""
        a, b = self.matrix()
        return np.asarray(uv, dtype=float) @ a.T + b

    def velocity_to_arena(self, duv: np.ndarray) -> np.ndarray:
        """(M, 2) surface velocities (axis lengths/s) → (M, 2) m/s (new array)."""
        a, _ = self.matrix()
        return np.asarray(duv, dtype=float) @ a.T

    @classmethod
    def from_dict(cls, d: dict, bounds: tuple[float, float, float, float] | None = None) -> Calibration:
        """Build from a config mapping (keys as the attributes); unknown keys are an error."""
        kw = check_keys(d, field_names(cls) | {"rotation_deg"}, "calibration", error=ValueError)
        kw.pop("rotation_deg", None)
        if "rotation_deg" in d:
            kw["rotation"] = math.radians(float(d["rotation_deg"]))
        if isinstance(kw.get("scale"), (int, float)):
            kw["scale"] = (float(kw["scale"]),) * 2
        for k in ("scale", "offset", "bounds"):
            if k in kw:
                try:
                    kw[k] = tuple(float(v) for v in kw[k])
                except (TypeError, ValueError):
                    raise ValueError(f"calibration {k} must be a list of numbers, got {kw[k]!r}") from None
        if bounds is not None and "bounds" not in kw:
            kw["bounds"] = tuple(bounds)
        for k in ("flip_x", "flip_y"):
            if k in kw and not isinstance(kw[k], bool):
                raise ValueError(f"calibration {k} must be true/false, got {kw[k]!r}")
        return cls(**kw)
