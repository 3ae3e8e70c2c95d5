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
import contextvars
import importlib
import importlib.abc
import importlib.machinery
import importlib.util
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from types import ModuleType
from typing import Any

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


_NOTES: contextvars.ContextVar[list[str] | None] = contextvars.ContextVar("swarmdeck_rps_notes", default=None)


def provide_get_cmap() -> None:
    """Within :func:`rps_aliases`: give ``matplotlib.cm`` back its ``get_cmap(name, lut)`` (removed in
    matplotlib 3.9) when it lacks one, for the block only. Called when matplotlib is loaded already or the
    facade hands out pyplot: importing matplotlib otherwise would write its folders into a script's HOME."""
    notes = _NOTES.get()
    if notes is None:
        return
    import matplotlib
    import matplotlib.cm as cm

    if hasattr(cm, "get_cmap"):
        return

    def _facade_get_cmap(name=None, lut=None):
        if GET_CMAP_NOTE not in notes:
            notes.append(GET_CMAP_NOTE)
        cmap = matplotlib.colormaps[name if name is not None else matplotlib.rcParams["image.cmap"]]
        return cmap if lut is None else cmap.resampled(lut)

    cm.get_cmap = _facade_get_cmap  # type: ignore[attr-defined]  # matplotlib 3.9 removed it; rps scripts call it


def quiet_canvas() -> None:
    """Within :func:`rps_aliases`: matplotlib's ``canvas.draw_idle()`` does nothing, for the block only.

    rps scripts ask for a redraw of their figures after every step (rps 2.x's EKF example: three figures). A window
    would coalesce those requests; headless (Agg) each one renders the whole figure, seconds per simulated second,
    for a picture nobody sees. ``savefig`` and an explicit ``canvas.draw()`` still render. Called where matplotlib
    is loaded already: on entering the block, when the facade hands out pyplot and when a Robotarium is built."""
    if _NOTES.get() is None or "matplotlib.backend_bases" not in sys.modules:
        return
    from matplotlib.backend_bases import FigureCanvasBase

    if FigureCanvasBase.draw_idle.__name__ == "_facade_draw_idle":
        return

    def _facade_draw_idle(self: Any, *args: Any, **kwargs: Any) -> None:
        """Nothing shows a figure under swarmdeck run: the redraw is skipped (savefig still draws)."""

    _facade_draw_idle.original = FigureCanvasBase.draw_idle  # type: ignore[attr-defined]
    FigureCanvasBase.draw_idle = _facade_draw_idle  # type: ignore[method-assign]


def _restore_canvas() -> None:
    bases = sys.modules.get("matplotlib.backend_bases")
    canvas = getattr(bases, "FigureCanvasBase", None)
    if canvas is not None and canvas.draw_idle.__name__ == "_facade_draw_idle":
        canvas.draw_idle = canvas.draw_idle.original


class _FacadeLoader(importlib.abc.Loader):
    """Loads ``rps.X`` as the facade's module ``swarmdeck.devices.rps.X`` (the same module object)."""

    def __init__(self, target: str) -> None:
        self.target = target

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType:
        return importlib.import_module(self.target)

    def exec_module(self, module: ModuleType) -> None:
        pass  # imported already by create_module


class _EmptyPackageLoader(importlib.abc.Loader):
    """Loads an empty package (``rps.examples`` and its folders: their modules are the script's own files)."""

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> None:
        return None  # the default module

    def exec_module(self, module: ModuleType) -> None:
        pass


class _FacadeFinder(importlib.abc.MetaPathFinder):
    """Finds ``rps`` and the ``rps.*`` names of :data:`MODULES` in the facade, and ``rps.examples.….NAME`` as the
    file ``NAME.py`` beside the script (rps's examples import their helpers so, e.g. the EKF example's
    ``from rps.examples.state_estimation.extended_kalman_filter.uni_ekf import UnicycleEKF``)."""

    def __init__(self, script_dir: Path | None = None) -> None:
        self.script_dir = script_dir

    def find_spec(self, fullname: str, path: Any = None, target: Any = None) -> importlib.machinery.ModuleSpec | None:
        if fullname == "rps":
            return importlib.machinery.ModuleSpec(fullname, _FacadeLoader(__name__), is_package=True)
        if fullname.startswith("rps.") and fullname[4:] in MODULES:
            sub = fullname[4:]
            return importlib.machinery.ModuleSpec(fullname, _FacadeLoader(f"{__name__}.{sub}"),
                                                  is_package=sub == "utilities")
        if (fullname == "rps.examples" or fullname.startswith("rps.examples.")) and self.script_dir is not None:
            name = fullname.rsplit(".", 1)[1]
            file = self.script_dir / f"{name}.py"
            if fullname != "rps.examples" and file.is_file():
                return importlib.util.spec_from_file_location(fullname, file)
            # the folders the script is in are rps.examples' packages (rps/examples/<topic>/<example>/)
            if fullname == "rps.examples" or name in (self.script_dir.name, *(p.name for p in self.script_dir.parents)):
                spec = importlib.machinery.ModuleSpec(fullname, _EmptyPackageLoader(), is_package=True)
                spec.submodule_search_locations = []
                return spec
        return None


@contextmanager
def rps_aliases(script_dir: Path | None = None) -> Iterator[list[str]]:
    """Within the block, ``rps`` and ``rps.*`` import these facade modules (and ``rps.examples.….NAME`` the file
    ``NAME.py`` in ``script_dir``, the folder of the script that runs).

    Also the numpy 1 API rps scripts rely on: ``np.mat`` (removed in numpy 2) is
    ``np.asmatrix`` within the block only; likewise matplotlib's ``cm.get_cmap(name, lut)`` (removed
    in matplotlib 3.9; rps-era scripts such as MARBLER's colour their markers with it). Yields a list
    that receives a note when the script used either.
    """
    import numpy as np

    notes: list[str] = []
    token = None
    saved = {k: v for k, v in sys.modules.items() if k == "rps" or k.startswith("rps.")}
    add_mat = not hasattr(np, "mat")
    finder = _FacadeFinder(script_dir)
    try:
        for k in saved:
            del sys.modules[k]
        sys.meta_path.insert(0, finder)  # `import rps.X` loads the facade's X then (and only then: the
        # barrier certificates pull in the safety filter and numba, ~1 s, which most scripts never need)
        if add_mat:
            def mat(data, dtype=None):
                import warnings

                if NP_MAT_NOTE not in notes:
                    notes.append(NP_MAT_NOTE)
                with warnings.catch_warnings():  # the note says it once; numpy would warn on every call
                    warnings.simplefilter("ignore", PendingDeprecationWarning)
                    return np.asmatrix(data, dtype)

            np.mat = mat  # type: ignore[attr-defined]
        token = _NOTES.set(notes)
        if "matplotlib.cm" in sys.modules:  # else when the facade hands out pyplot (figure.pyplot)
            provide_get_cmap()
        quiet_canvas()
        yield notes
    finally:
        if finder in sys.meta_path:
            sys.meta_path.remove(finder)
        if add_mat and getattr(np, "mat", None) is mat:
            del np.mat  # type: ignore[attr-defined]
        _restore_canvas()
        if token is not None:
            _NOTES.reset(token)
        cm = sys.modules.get("matplotlib.cm")
        if cm is not None and getattr(getattr(cm, "get_cmap", None), "__name__", "") == "_facade_get_cmap":
            del cm.get_cmap
        for k in [k for k in sys.modules if k == "rps" or k.startswith("rps.")]:
            del sys.modules[k]
        sys.modules.update(saved)
