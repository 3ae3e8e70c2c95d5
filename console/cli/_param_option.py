"""``--param NAME=VALUE``: one value of a parameter the script declares (``swarmdeck run``, ``swarmdeck submit``)."""
from __future__ import annotations

from typing import Any

from swarmdeck.console.cli import UsageError


def param_values(specs: list[str]) -> dict[str, Any] | None:
    """``--param NAME=VALUE`` options as {name: value} (None: none given); UsageError for a range or a malformed
    one. The value is read as ``swarmdeck sweep --param`` reads a one-point axis."""
    if not specs:
        return None
    from swarmdeck.console.sweep.design import DesignError, parse_axis

    values: dict[str, Any] = {}
    for spec in specs:
        try:
            axis = parse_axis(spec)
        except DesignError as exc:
            raise UsageError(str(exc)) from None
        if len(axis.values) != 1:
            raise UsageError(f"--param {spec!r}: one value per parameter here (`swarmdeck sweep` sweeps ranges)")
        values[axis.name] = axis.values[0]
    return values
