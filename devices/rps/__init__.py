"""An rps-compatible facade: run Robotarium Python simulator scripts unchanged on swarmdeck.

``swarmdeck run --rps script.py`` makes ``import rps.robotarium`` and
``from rps.utilities.… import …`` resolve to these modules for the run only
(nothing named ``rps`` is installed, so a real rps is never shadowed). The
arrays are rps's ``(3, N)`` / ``(2, N)`` columns; the robots underneath are a
:class:`swarmdeck.devices.Arena`, so every command still goes through
swarmdeck's safety filter, wheel limits and validation — without rps's
defects (REFERENCE.md §2): poses are copies, arguments are never modified,
integer initial conditions are rejected, wheels are scaled not clipped.
"""
import sys
from contextlib import contextmanager
from collections.abc import Iterator

MODULES = (
    "robotarium",
    "robotarium_abc",
    "utilities",
    "utilities.barrier_certificates",
    "utilities.controllers",
    "utilities.graph",
    "utilities.misc",
    "utilities.transformations",
)


@contextmanager
def rps_aliases() -> Iterator[None]:
    """Within the block, ``rps`` and ``rps.*`` import these facade modules."""
    import importlib

    saved = {k: v for k, v in sys.modules.items() if k == "rps" or k.startswith("rps.")}
    try:
        sys.modules["rps"] = sys.modules[__name__]
        for name in MODULES:
            sys.modules[f"rps.{name}"] = importlib.import_module(f"{__name__}.{name}")
        yield
    finally:
        for k in [k for k in sys.modules if k == "rps" or k.startswith("rps.")]:
            del sys.modules[k]
        sys.modules.update(saved)
