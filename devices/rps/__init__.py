"""An rps-compatible facade: run Robotarium Python simulator scripts unchanged on swarmdeck.

``swarmdeck run --rps script.py`` makes ``import rps.robotarium`` and
``from rps.utilities.… import …`` resolve to these modules for the run only
(nothing named ``rps`` is installed, so a real rps is never shadowed), and
provides ``np.mat`` under numpy 2 for that run only. The
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
    "utilities.barrier_certificates2",
    "utilities.controllers",
    "utilities.graph",
    "utilities.misc",
    "utilities.transformations",
)


NP_MAT_NOTE = ("the script used np.mat, which numpy 2 removed: it was provided as np.asmatrix for this "
               "run only (rps scripts written for numpy 1 use it for initial conditions)")
GET_CMAP_NOTE = ("the script used matplotlib.cm.get_cmap (plt.cm.get_cmap), which matplotlib 3.9 removed: it was "
                 "provided as matplotlib.colormaps[name].resampled(lut) for this run only")


def _matplotlib_cm():
    """``matplotlib.cm`` (None where matplotlib is missing)."""
    try:
        import matplotlib.cm
    except ImportError:  # pragma: no cover - matplotlib is a dependency
        return None
    return matplotlib.cm


@contextmanager
def rps_aliases() -> Iterator[list[str]]:
    """Within the block, ``rps`` and ``rps.*`` import these facade modules.

    Also the numpy 1 API rps scripts rely on: ``np.mat`` (removed in numpy 2) is
    ``np.asmatrix`` within the block only; likewise matplotlib's ``cm.get_cmap(name, lut)`` (removed
    in matplotlib 3.9; rps-era scripts such as MARBLER's colour their markers with it). Yields a list
    that receives a note when the script used either.
    """
    import importlib

    import numpy as np

    notes: list[str] = []
    add_cmap = False
    saved = {k: v for k, v in sys.modules.items() if k == "rps" or k.startswith("rps.")}
    add_mat = not hasattr(np, "mat")
    try:
        sys.modules["rps"] = sys.modules[__name__]
        for name in MODULES:
            sys.modules[f"rps.{name}"] = importlib.import_module(f"{__name__}.{name}")
        if add_mat:
            def mat(data, dtype=None):
                import warnings

                if NP_MAT_NOTE not in notes:
                    notes.append(NP_MAT_NOTE)
                with warnings.catch_warnings():  # the note says it once; numpy would warn on every call
                    warnings.simplefilter("ignore", PendingDeprecationWarning)
                    return np.asmatrix(data, dtype)

            np.mat = mat  # type: ignore[attr-defined]
        cm = _matplotlib_cm()
        add_cmap = cm is not None and not hasattr(cm, "get_cmap")
        if add_cmap:
            def get_cmap(name=None, lut=None):
                import matplotlib

                if GET_CMAP_NOTE not in notes:
                    notes.append(GET_CMAP_NOTE)
                cmap = matplotlib.colormaps[name if name is not None else matplotlib.rcParams["image.cmap"]]
                return cmap if lut is None else cmap.resampled(lut)

            cm.get_cmap = get_cmap
        yield notes
    finally:
        if add_mat and getattr(np, "mat", None) is mat:
            del np.mat  # type: ignore[attr-defined]
        if add_cmap and getattr(cm, "get_cmap", None) is get_cmap:
            del cm.get_cmap
        for k in [k for k in sys.modules if k == "rps" or k.startswith("rps.")]:
            del sys.modules[k]
        sys.modules.update(saved)
