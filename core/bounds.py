"""The arena rectangle: its type with its geometry, the default floor and its validation.

Arena frame (DESIGN.md "Conventions"): origin at the centre, x right, y up, metres.
``bounds = (x_min, x_max, y_min, y_max)``; the Robotarium floor is 3.2 m × 2.0 m (REFERENCE.md §1).

:class:`Bounds` is a :class:`~typing.NamedTuple`, so ``x0, x1, y0, y1 = bounds`` keeps working and a
plain 4-tuple compares equal to it; code that needs the rectangle's width, centre, a containment
test or a clip asks the type (``Bounds.of(bounds).width``) instead of re-deriving it.
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray


class Bounds(NamedTuple):
    """An axis-aligned rectangle in the arena frame, m: ``(x_min, x_max, y_min, y_max)``."""

    x_min: float
    x_max: float
    y_min: float
    y_max: float

    @classmethod
    def of(cls, bounds: tuple[float, float, float, float] | Bounds) -> Bounds:
        """``bounds`` (any 4-sequence ``(x_min, x_max, y_min, y_max)``, m) as a :class:`Bounds`, unchecked
        (see :func:`check_bounds` for validation of outside input)."""
        return bounds if isinstance(bounds, Bounds) else cls(*bounds)

    def __repr__(self) -> str:
        """As the plain tuple ``(x_min, x_max, y_min, y_max)``: messages and logs that quote a bounds read as before."""
        return repr(tuple(self))

    @property
    def width(self) -> float:
        """Extent along x, m: ``x_max − x_min``."""
        return self.x_max - self.x_min

    @property
    def height(self) -> float:
        """Extent along y, m: ``y_max − y_min``."""
        return self.y_max - self.y_min

    @property
    def area(self) -> float:
        """``width · height``, m²."""
        return (self.x_max - self.x_min) * (self.y_max - self.y_min)

    @property
    def centre(self) -> tuple[float, float]:
        """The rectangle's centre ``(x, y)``, m."""
        return ((self.x_min + self.x_max) / 2, (self.y_min + self.y_max) / 2)

    def shrunk(self, margin: float) -> Bounds:
        """The rectangle shrunk by ``margin`` m on every side (grown for ``margin`` < 0), unchecked."""
        return Bounds(self.x_min + margin, self.x_max - margin, self.y_min + margin, self.y_max - margin)

    def contains(self, points: ArrayLike, margin: float = 0.0) -> NDArray[np.bool_]:
        """Which of ``points`` (``(..., 2)`` rows ``[x, y]``, m; extra columns such as θ are ignored) lie
        in the rectangle shrunk by ``margin`` m on every side, edges included; shape ``points.shape[:-1]``."""
        p = np.asarray(points, dtype=float)
        x, y = p[..., 0], p[..., 1]
        return ((x >= self.x_min + margin) & (x <= self.x_max - margin)
                & (y >= self.y_min + margin) & (y <= self.y_max - margin))

    def clip(self, points: ArrayLike, margin: float = 0.0) -> NDArray[np.float64]:
        """A new array: ``points`` (``(..., 2)`` or ``(..., 3)``, m) with x and y clipped into the rectangle
        shrunk by ``margin`` m on every side; other columns unchanged."""
        out = np.array(points, dtype=float)
        out[..., 0] = np.clip(out[..., 0], self.x_min + margin, self.x_max - margin)
        out[..., 1] = np.clip(out[..., 1], self.y_min + margin, self.y_max - margin)
        return out


#: The Robotarium floor, m (REFERENCE.md §1).
DEFAULT_BOUNDS: Bounds = Bounds(-1.6, 1.6, -1.0, 1.0)


def check_bounds(bounds: object, name: str = "bounds", error: type[Exception] = ValueError) -> Bounds:
    """``bounds`` as a :class:`Bounds` of 4 floats; ``error`` naming ``name`` unless it is 4 finite numbers
    with x_min < x_max and y_min < y_max."""
    try:
        b = tuple(float(v) for v in bounds)  # type: ignore[attr-defined]  # anything iterable; TypeError otherwise
    except (TypeError, ValueError):
        b = ()
    if len(b) != 4 or not all(math.isfinite(v) for v in b) or not (b[0] < b[1] and b[2] < b[3]):
        raise error(f"{name} must be (x_min, x_max, y_min, y_max): 4 finite numbers with min < max, "
                    f"got {bounds!r}")
    return Bounds(*b)
