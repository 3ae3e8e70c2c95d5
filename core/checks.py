"""Validation shared by the configuration dataclasses of :mod:`swarmdeck.devices`."""
from __future__ import annotations

import math
import numbers


def require_positive(obj: object, names: tuple[str, ...], unit: str = "", *, allow_zero: bool = False) -> None:
    """Raise ValueError naming ``Class.field`` unless each field is a finite number > 0 (>= 0 with ``allow_zero``).

    ``unit`` is named in the message (e.g. ``"s"``); NaN, inf, bools and non-numbers are rejected.
    """
    cls = type(obj).__name__
    for name in names:
        x = getattr(obj, name)
        ok = isinstance(x, numbers.Real) and not isinstance(x, bool) and math.isfinite(x) and (x >= 0 if allow_zero else x > 0)
        if not ok:
            what = "a finite number >= 0" if allow_zero else "a positive finite number"
            raise ValueError(f"{cls}.{name} must be {what}{' of ' + unit if unit else ''}, got {x!r}")
