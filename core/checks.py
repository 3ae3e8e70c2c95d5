""""Finite and in range": the value checks of every configuration dataclass, written once.

:func:`in_range` is the predicate (a real number, not a bool, finite, inside the interval);
:func:`require_in_range` raises with the one message form ``"<name> must be in [lo, hi] <unit>,
got <value>"``; :func:`require_positive` checks several fields of one object and names
``Class.field``. Configuration objects call these from ``__post_init__``; loading from files
is :mod:`swarmdeck.core.config`.
"""
from __future__ import annotations

import math
import numbers
from typing import cast


def in_range(x: object, lo: float = -math.inf, hi: float = math.inf, *, lo_open: bool = False,
             hi_open: bool = False, integer: bool = False) -> bool:
    """True if ``x`` is a finite real number (an int with ``integer``; never a bool) in the interval
    from ``lo`` to ``hi`` (closed unless ``lo_open``/``hi_open``). NaN and inf are never in range."""
    kind = numbers.Integral if integer else numbers.Real
    if isinstance(x, bool) or not isinstance(x, kind):
        return False
    if not isinstance(x, numbers.Integral) and not math.isfinite(x):  # ints are finite (and may not fit a float)
        return False
    v = cast(float, x)  # a Real: compares with floats (typeshed's numbers.Real declares no operators)
    return bool((v > lo if lo_open else v >= lo) and (v < hi if hi_open else v <= hi))


def describe_range(lo: float = -math.inf, hi: float = math.inf, *, lo_open: bool = False, hi_open: bool = False,
                   integer: bool = False) -> str:
    """The interval in words: ``"in [0.11, 0.4]"``, ``"> 0"``, ``"an integer in [1, 200]"``, ``"a finite number"``."""
    if math.isinf(lo) and math.isinf(hi):
        text = "finite"
    elif math.isinf(hi):
        text = f"{'>' if lo_open else '>='} {lo:g}"
    elif math.isinf(lo):
        text = f"{'<' if hi_open else '<='} {hi:g}"
    else:
        text = f"in {'(' if lo_open else '['}{lo:g}, {hi:g}{')' if hi_open else ']'}"
    if integer:
        return f"an integer {text}" if text != "finite" else "an integer"
    return text if text != "finite" else "a finite number"


def require_in_range(value: object, name: str, lo: float = -math.inf, hi: float = math.inf, *, unit: str = "",
                     lo_open: bool = False, hi_open: bool = False, integer: bool = False,
                     error: type[Exception] = ValueError) -> None:
    """Raise ``error("<name> must be <range> <unit>, got <value!r>")`` unless :func:`in_range` holds."""
    if not in_range(value, lo, hi, lo_open=lo_open, hi_open=hi_open, integer=integer):
        what = describe_range(lo, hi, lo_open=lo_open, hi_open=hi_open, integer=integer)
        raise error(f"{name} must be {what}{' ' + unit if unit else ''}, got {value!r}")


def require_positive(obj: object, names: tuple[str, ...], unit: str = "", *, allow_zero: bool = False) -> None:
    """Raise ValueError naming ``Class.field`` unless each field is a finite number > 0 (>= 0 with ``allow_zero``).

    ``unit`` is named in the message (e.g. ``"s"``); NaN, inf, bools and non-numbers are rejected.
    """
    cls = type(obj).__name__
    for name in names:
        x = getattr(obj, name)
        if not in_range(x, 0.0, lo_open=not allow_zero):
            what = "a finite number >= 0" if allow_zero else "a positive finite number"
            raise ValueError(f"{cls}.{name} must be {what}{' of ' + unit if unit else ''}, got {x!r}")
