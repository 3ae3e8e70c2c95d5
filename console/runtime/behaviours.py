"""Behaviours the console can run: nominal single-integrator velocities for the look-ahead points.

Each behaviour is called once per tick with a :class:`TickInput` and returns
``(nominal (N, 2) m/s, coverage_state | None)``. The loop validates the result
(shape, finiteness), saturates it to the speed limit and passes it through the
safety filter, so a behaviour never has to be safe itself.

Names (``--behaviour``): ``coverage`` (TVD-D1 or another law on the console's
density), ``rendezvous`` (consensus, paper §V-A), ``formation`` (rigid polygon,
paper §V-B), ``goto`` (go to goal positions), ``decentralised`` (rendezvous by messages only over a lossy
network, console/runtime/decentralised_behaviour.py) and ``script:PATH`` (a user's
Python file defining ``behaviour(poses, t) -> (N, 2)``).
"""
from __future__ import annotations

import importlib.util
import math
import sys
import weakref
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from swarmdeck.console.runtime.deadline import DeadlineCaller
from swarmdeck.console.runtime.params import BehaviourError, BehaviourParams
from swarmdeck.core.annotations import Annotations
from swarmdeck.core.bounds import Bounds
from swarmdeck.core.graphs import complete_laplacian, rigid_formation
from swarmdeck.coverage.group import consensus, formation_control
from swarmdeck.devices.controllers import si_position_controller

if TYPE_CHECKING:
    from swarmdeck.coverage.density import Density

FloatArray = NDArray[np.float64]
BUILTIN = ("coverage", "rendezvous", "formation", "goto", "decentralised")


@dataclass(frozen=True)
class TickInput:
    """What a behaviour sees: poses (N, 3), look-ahead points (N, 2), run time t (s), the density
    (any ``.at(t)`` object), the arena bounds and the speed limit (m/s); the loop also gives the
    robot ids (N,) and which robots have a fresh pose, seen (N,) (fleet upkeep uses them)."""

    poses: FloatArray
    points: FloatArray
    t: float
    density: Density
    bounds: tuple[float, float, float, float]
    max_speed: float
    ids: NDArray[np.int64] | None = None
    seen: NDArray[np.bool_] | None = None


class Behaviour(Protocol):
    """``name``; called once per tick. Optional: ``health() -> str`` (a line in the Frame's health,
    under the behaviour's name), ``fixed(ids) -> (N,) bool`` (robots the barrier must treat as fixed
    obstacles this tick: they get zero and are never pushed aside, e.g. robots docked on a charger),
    ``close()``."""

    name: str

    def __call__(self, tick: TickInput) -> tuple[Any, Any | None]: ...


# A behaviour's optional capabilities (the loop checks them with isinstance; closing is core.ports.Closeable).

@runtime_checkable
class HoldsRobots(Protocol):
    """Holds some robots in place this tick (e.g. docked on a charger): the barrier keeps them as fixed obstacles."""

    def fixed(self, ids: NDArray[np.int64]) -> NDArray[np.bool_]:
        """``(N,)`` True for the robots ``ids`` (N,) held in place."""


@runtime_checkable
class DrawsAnnotations(Protocol):
    """Draws on the arena: the Frame's ``annotations`` of this tick (e.g. a sandboxed script's drawing)."""

    def annotations(self, time: float) -> Annotations:
        """What to draw in the tick at run time ``time`` s (within the caps: ``Annotator.collect``)."""


@runtime_checkable
class ReportsHealth(Protocol):
    """Has a line for the Frame's health, under the behaviour's name (a script's worker, a maneuver's progress)."""

    def health(self) -> str: ...


@runtime_checkable
class ReportsNetwork(Protocol):
    """Runs the robots over a network (``swarmdeck.network``): the Frame's ``network`` is its links and traffic."""

    def network_frame(self, dt: float) -> Any: ...


@runtime_checkable
class HasBarrierSettings(Protocol):
    """Runs with its own barrier settings (``BarrierConfig`` fields, e.g. ``{"class_k": "linear", "gamma": 20.0}``)
    instead of the operator's, while it is the behaviour."""

    barrier: Mapping[str, Any]


class Coverage:
    """Coverage control on the console's density (``swarmdeck.coverage.CoverageController``)."""

    name = "coverage"

    def __init__(self, params: BehaviourParams, bounds: Bounds,
                 max_speed: float, safety_distance: float) -> None:
        from swarmdeck.coverage import CoverageConfig, CoverageController

        self._config = CoverageConfig(law=params.law, kappa=params.kappa, max_speed=max_speed, bounds=bounds,
                                      safety_distance=safety_distance)
        self._make = CoverageController
        self._ctrl: Any = None

    def __call__(self, tick: TickInput) -> tuple[FloatArray, Any]:
        if self._ctrl is None:
            self._ctrl = self._make(self._config, tick.density)
        elif self._ctrl.density is not tick.density:
            self._ctrl.density = tick.density
        return self._ctrl(tick.points, tick.t)


class Rendezvous:
    """Consensus on the complete graph, scaled by 1/N: u_i = gain · (mean(p) − p_i) (paper §V-A)."""

    name = "rendezvous"

    def __init__(self, params: BehaviourParams) -> None:
        self.gain = params.gain

    def __call__(self, tick: TickInput) -> tuple[FloatArray, None]:
        n = len(tick.points)
        if n < 2:
            return np.zeros((n, 2)), None
        return consensus(tick.points, complete_laplacian(n), self.gain / n), None


class Formation:
    """Rigid regular N-gon by edge-tension gradient descent (paper §V-B), plus a weak pull
    of the group's centre to the arena centre so the formation stays on the floor."""

    name = "formation"

    def __init__(self, params: BehaviourParams) -> None:
        self.edge, self.alpha = params.formation_edge, params.formation_gain
        self._cache: tuple[int, Any, Any] | None = None

    def __call__(self, tick: TickInput) -> tuple[FloatArray, None]:
        n = len(tick.points)
        if n < 3:
            return Rendezvous(BehaviourParams())(tick)
        if self._cache is None or self._cache[0] != n:
            _, edges, lengths = rigid_formation(n, self.edge)
            self._cache = (n, edges, lengths)
        _, edges, lengths = self._cache
        u = formation_control(tick.points, edges, lengths, self.alpha)
        centre = np.array(Bounds.of(tick.bounds).centre)
        return u + 0.3 * (centre - tick.points.mean(axis=0)), None


def default_goals(n: int, bounds: tuple[float, float, float, float], margin: float = 0.3) -> FloatArray:
    """``(n, 2)`` goal positions on a grid filling the arena (m), as square as the arena allows."""
    b = Bounds.of(bounds)
    inner = b.shrunk(margin)
    w, h = b.width - 2 * margin, b.height - 2 * margin
    cols = max(1, int(math.ceil(math.sqrt(n * w / max(h, 1e-9)))))
    rows = int(math.ceil(n / cols))
    xs = np.linspace(inner.x_min, inner.x_max, cols) if cols > 1 else np.array([b.centre[0]])
    ys = np.linspace(inner.y_max, inner.y_min, rows) if rows > 1 else np.array([b.centre[1]])
    gx, gy = np.meshgrid(xs, ys)
    return np.column_stack((gx.ravel(), gy.ravel()))[:n]


def cluster_goals(n: int, centre: tuple[float, float], bounds: tuple[float, float, float, float],
                  spacing: float = 0.25, margin: float = 0.15) -> FloatArray:
    """``(n, 2)`` goals on a hexagonal lattice (pitch ``spacing`` m) nearest to ``centre``, shifted so
    all lie at least ``margin`` m inside the arena (when the arena is large enough)."""
    k = int(math.ceil(math.sqrt(n))) + 2
    i, j = np.meshgrid(np.arange(-k, k + 1), np.arange(-k, k + 1))
    pts = np.column_stack(((i + 0.5 * (j % 2)).ravel() * spacing, (j * math.sqrt(3) / 2).ravel() * spacing))
    pts = pts[np.argsort(np.linalg.norm(pts, axis=1), kind="stable")[:n]] + np.asarray(centre, dtype=float)
    inner = Bounds.of(bounds).shrunk(margin)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    shift = (np.maximum(np.array([inner.x_min, inner.y_min]) - lo, 0.0)
             + np.minimum(np.array([inner.x_max, inner.y_max]) - hi, 0.0))
    return pts + shift


def goto_goals(n: int, bounds: tuple[float, float, float, float], goals: Any = None,
               centre: tuple[float, float] | None = None) -> FloatArray:
    """The ``(n, 2)`` goals (m) ``goto`` drives ``n`` robots to: ``goals`` when it has ``n`` rows, else a
    cluster around ``centre`` (:func:`cluster_goals`), else a grid over the arena (:func:`default_goals`)."""
    if goals is not None and len(goals) == n:
        return np.asarray(goals, dtype=float)
    return default_goals(n, bounds) if centre is None else cluster_goals(n, centre, bounds)


def goal_params(params: BehaviourParams) -> dict[str, Any]:
    """What a Frame's ``params`` carries of the goals, so the scene draws them live and in playback:
    ``goal_centre_x/_y`` (m) and ``goals`` (``"x,y;x,y;…"``, mm precision), each only when set."""
    out: dict[str, Any] = {}
    if params.goal_centre is not None:
        out["goal_centre_x"], out["goal_centre_y"] = (float(v) for v in params.goal_centre)
    if params.goals is not None:
        out["goals"] = ";".join(f"{x:.3f},{y:.3f}" for x, y in np.asarray(params.goals, dtype=float))
    return out


def goals_of_frame(params: Mapping[str, Any], n: int, bounds: tuple[float, float, float, float]) -> FloatArray:
    """The goto goals of a Frame from its ``params`` (:func:`goal_params`); malformed entries are ignored."""
    goals = None
    text = params.get("goals")
    if isinstance(text, str) and text:
        try:
            goals = np.array([[float(v) for v in pair.split(",")] for pair in text.split(";")]).reshape(-1, 2)
        except ValueError:
            goals = None
    cx, cy = params.get("goal_centre_x"), params.get("goal_centre_y")
    centre = (float(cx), float(cy)) if isinstance(cx, (int, float)) and isinstance(cy, (int, float)) else None
    return goto_goals(n, bounds, goals, centre)


class GoTo:
    """Go to goal positions with the single-integrator position controller (look-ahead points)."""

    name = "goto"

    def __init__(self, params: BehaviourParams, bounds: tuple[float, float, float, float]) -> None:
        self.gain = params.gain
        self.bounds = bounds
        self.goals = None if params.goals is None else np.asarray(params.goals, dtype=float)
        self.centre = params.goal_centre

    def __call__(self, tick: TickInput) -> tuple[FloatArray, None]:
        n = len(tick.points)
        goals = goto_goals(n, self.bounds, self.goals, self.centre)
        return si_position_controller(tick.points, goals, self.gain, tick.max_speed), None


class Script:
    """A user's file defining ``behaviour(poses, t) -> (N, 2)`` SI velocities of the look-ahead points.

    ``poses`` is a fresh ``(N, 3)`` copy, ``t`` the run time in s. Whatever the
    function raises or returns is checked by the loop: robots stop, the
    console shows the message, the loop keeps running. The function runs on a
    worker thread with a deadline of ``budget`` s per tick
    (:class:`~swarmdeck.console.runtime.deadline.DeadlineCaller`): a call that
    takes longer is abandoned for the tick (TickBudgetExceeded: robots stop), and
    while it still runs every later tick is abandoned at once.
    """

    def __init__(self, path: str | Path, budget: float = 0.0165) -> None:
        self.path = Path(path)
        self.name = f"script:{path}"
        self.func = load_script(self.path)
        self.budget = float(budget)
        self.caller = DeadlineCaller(f"swarmdeck-script-{self.path.name}")
        weakref.finalize(self, self.caller.close)  # an idle worker ends with its behaviour

    def __call__(self, tick: TickInput) -> tuple[Any, None]:
        return self.caller.call(self.func, np.array(tick.poses), float(tick.t), budget=self.budget), None

    def health(self) -> str:
        """The console's health line: ticks abandoned to the budget, and whether a call still hangs."""
        c = self.caller
        line = f"budget {self.budget * 1e3:.0f} ms, {c.abandoned} ticks abandoned"
        return line + (" (a call is still running)" if c.busy else "")

    def close(self) -> None:
        self.caller.close()


def load_script(path: Path) -> Callable[..., Any]:
    """Import a behaviour script and return its ``behaviour`` function (BehaviourError otherwise)."""
    if not path.is_file():
        raise BehaviourError(f"behaviour script {path} does not exist")
    mod_name = f"swarmdeck_user_behaviour_{abs(hash(str(path.resolve())))}"
    spec = importlib.util.spec_from_file_location(mod_name, path)
    if spec is None or spec.loader is None:
        raise BehaviourError(f"cannot load {path} as a Python file")
    module = importlib.util.module_from_spec(spec)
    try:
        spec.loader.exec_module(module)
    except Exception as exc:  # user code: report, never crash the console
        raise BehaviourError(f"behaviour script {path} failed to import: {type(exc).__name__}: {exc}") from exc
    finally:
        sys.modules.pop(mod_name, None)
    func = getattr(module, "behaviour", None)
    if not callable(func):
        raise BehaviourError(f"behaviour script {path} must define a function behaviour(poses, t) -> (N, 2) array")
    return func


def make_behaviour(name: str, params: BehaviourParams, bounds: Bounds,
                   max_speed: float, safety_distance: float, *, script_budget: float = 0.0165,
                   coverage_worker: bool = False) -> Behaviour:
    """The behaviour called ``name`` (see the module docstring); BehaviourError for unknown names.
    ``script_budget``: s a ``script:`` behaviour may take per tick (:class:`Script`); ``coverage_worker``:
    ``coverage`` runs two ticks behind on worker threads (:mod:`swarmdeck.console.runtime.coverage_worker`)."""
    if name == "coverage":
        if coverage_worker:
            from swarmdeck.console.runtime.coverage_worker import PipelinedCoverage

            return PipelinedCoverage(params, bounds, max_speed, safety_distance)
        return Coverage(params, bounds, max_speed, safety_distance)
    if name == "rendezvous":
        return Rendezvous(params)
    if name == "formation":
        return Formation(params)
    if name == "goto":
        return GoTo(params, bounds)
    if name == "decentralised":
        from swarmdeck.console.runtime.decentralised_behaviour import DecentralisedRendezvous

        return DecentralisedRendezvous(params)
    if name.startswith("script:"):
        path = name[len("script:"):]
        if not path:
            raise BehaviourError("script: needs a path, e.g. --behaviour script:my_behaviour.py")
        return Script(path, script_budget)
    raise BehaviourError(f"unknown behaviour {name!r}: use one of {', '.join(BUILTIN)} or script:PATH")
