"""The arena rectangle: its type, the default floor and its validation.

Arena frame (DESIGN.md "Conventions"): origin at the centre, x right, y up, metres.
``bounds = (x_min, x_max, y_min, y_max)``; the Robotarium floor is 3.2 m × 2.0 m.
"""
from __future__ import annotations

import math

Bounds = tuple[float, float, float, float]

#: The Robotarium floor, m (REFERENCE.md §1).
DEFAULT_BOUNDS: Bounds = (-1.6, 1.6, -1.0, 1.0)


def check_bounds(bounds: object, name: str = "bounds", error: type[Exception] = ValueError) -> Bounds:
    """``bounds`` as a tuple of 4 floats; ``error`` naming ``name`` unless it is 4 finite numbers with
    x_min < x_max and y_min < y_max."""
    try:
        b = tuple(float(v) for v in bounds)  # type: ignore[attr-defined]  # anything iterable; TypeError otherwise
    except (TypeError, ValueError):
        b = ()
    if len(b) != 4 or not all(math.isfinite(v) for v in b) or not (b[0] < b[1] and b[2] < b[3]):
        raise error(f"{name} must be (x_min, x_max, y_min, y_max): 4 finite numbers with min < max, "
                    f"got {bounds!r}")
    return (b[0], b[1], b[2], b[3])
