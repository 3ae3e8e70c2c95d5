"""The operator's parameters, each declared once (DESIGN.md "Operator parameters").

Every parameter the operator can set is one field of one frozen dataclass below, declared with
:func:`param`: its default (from REFERENCE.md), unit, range or choices, GUI label and step, and the
key it carries in ``Frame.params``. Everything else is generated from that one line:

* **validation** — :func:`check_params` (each class's ``__post_init__``) names the parameter, its
  range and unit in the error;
* **TOML** — the ``[behaviour]``, ``[safety]``, ``[density]`` tables map key = field name, the
  ``[console]`` table through :func:`toml_keys` (a field's ``toml`` name, e.g. ``robots``);
* **GUI widgets** — :func:`gui_fields` (slider, dropdown or checkbox from the declaration;
  ``console/web/gui.py`` builds them in a loop);
* **Frame.params** — :func:`frame_params` (fields with a ``frame`` key, in declaration order);
* **the recording's config** — :func:`to_dict` / :func:`from_dict` (re-simulation rebuilds the
  :class:`LoopConfig` from it) and :func:`frame_keys` (which ``Frame.params`` key is which field).

To add a parameter: add one ``name: type = param(...)`` line to the class it belongs to (and read
it where it acts). See ``/docs`` (architecture, "operator parameters").
"""
from __future__ import annotations

import dataclasses
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any, TypeVar

import numpy as np

from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds
from swarmdeck.core.checks import in_range, require_in_range
from swarmdeck.core.config import floats
from swarmdeck.core.constants import CONTROL_PERIOD, ROBOT_DIAMETER, SAFETY_DISTANCE
from swarmdeck.core.errors import SwarmdeckError
from swarmdeck.core.obstacles import Obstacles
from swarmdeck.coverage.densities import s1_density
from swarmdeck.devices import ArenaConfig

#: Coverage laws a ``law`` may name (swarmdeck.coverage).
LAWS = ("lloyd", "lloyd-ff", "tvd-d1", "tvd-dk")

T = TypeVar("T")
_KEY = "swarmdeck.param"


class BehaviourError(ValueError, SwarmdeckError):
    """A behaviour name, script or parameter that cannot be used."""


@dataclass(frozen=True)
class Spec:
    """One parameter's declaration (the metadata of its dataclass field).

    unit: SI unit shown in errors and labels. lo, hi: the allowed range (``lo_open``/``hi_open``: bound
    excluded; ``integer``: whole numbers only); None: no check. choices: the allowed strings.
    label, step: the GUI widget (no label: not in the GUI). frame: its key in ``Frame.params``
    (None: not in the Frame). toml: its key in the ``[console]`` TOML table when that differs from the
    field name. shown: the name errors use (default: the field's). error: the exception type of a bad value.
    """

    unit: str = ""
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False
    integer: bool = False
    choices: tuple[str, ...] | None = None
    label: str | None = None
    step: float | None = None
    frame: str | None = None
    toml: str | None = None
    shown: str | None = None
    error: type[Exception] = ValueError


def param(default: Any = None, *, factory: Any = None, **spec: Any) -> Any:
    """A dataclass field declaring one operator parameter (keywords: :class:`Spec`)."""
    meta = {_KEY: Spec(**spec)}
    if factory is not None:
        return field(default_factory=factory, metadata=meta)
    return field(default=default, metadata=meta)


def specs(cls_or_obj: Any) -> Iterator[tuple[str, Spec]]:
    """``(field name, Spec)`` of every declared parameter of a params class, in declaration order."""
    for f in dataclasses.fields(cls_or_obj):
        s = f.metadata.get(_KEY)
        if s is not None:
            yield f.name, s


def check_params(obj: Any) -> None:
    """Validate every declared parameter of ``obj`` against its :class:`Spec` (the class's error type
    naming the parameter, its range and unit)."""
    for name, s in specs(obj):
        value = getattr(obj, name)
        shown = s.shown or name
        if s.choices is not None:
            if value not in s.choices:
                raise s.error(f"{shown} must be one of {', '.join(repr(c) for c in s.choices)}, got {value!r}")
        elif s.lo is not None or s.hi is not None or s.integer:
            if value is None:
                continue
            require_in_range(value, shown, -np.inf if s.lo is None else s.lo, np.inf if s.hi is None else s.hi,
                             unit=s.unit, lo_open=s.lo_open, hi_open=s.hi_open, integer=s.integer, error=s.error)


def _number(value: Any) -> Any:
    return float(value) if isinstance(value, int) and not isinstance(value, bool) else value


def _points(value: Any) -> Any:
    return None if value is None else tuple(floats(row) for row in value)


def _point(value: Any) -> Any:
    return None if value is None else floats(value)


def converters(cls: type) -> dict[str, Any]:
    """Field name -> how a TOML/JSON value becomes the field's type, from the declared types: whole
    numbers for float fields as floats, arrays as tuples of floats (TypeError/ValueError when they are not)."""
    out: dict[str, Any] = {}
    for f in dataclasses.fields(cls):
        if _KEY not in f.metadata:
            continue
        t = str(f.type)
        if t.startswith("tuple[tuple"):
            out[f.name] = _points
        elif t.startswith(("tuple", "Bounds")):
            out[f.name] = _point
        elif t.startswith("float"):
            out[f.name] = _number
    return out


def gui_fields(cls: type) -> list[tuple[str, Spec]]:
    """The parameters of ``cls`` that have a GUI widget (a ``label``), in declaration order."""
    return [(name, s) for name, s in specs(cls) if s.label is not None]


def toml_keys(cls: type) -> dict[str, str]:
    """TOML key -> field name of every declared parameter of ``cls`` (the ``toml`` name or the field's)."""
    return {s.toml or name: name for name, s in specs(cls)}


# ---------------------------------------------------------------------------------------------- the parameters
@dataclass(frozen=True)
class BehaviourParams:
    """Parameters of the built-in behaviours (GUI and ``[behaviour]`` in the config file).

    goals: ``(N, 2)`` go-to positions, m, or None for a grid spread over the arena. goal_centre:
    ``(x, y)`` m — when set (and ``goals`` is None), robots gather in a hexagonal cluster (0.25 m
    spacing) there (the console's shift-click).
    """

    kappa: float = param(1.0, unit="1/s", lo=0.1, hi=5.0, label="κ (coverage gain)", step=0.1, frame="kappa",
                         error=BehaviourError)
    law: str = param("tvd-d1", choices=LAWS, label="Coverage law", frame="law", error=BehaviourError)
    gain: float = param(1.0, unit="1/s", lo=0.1, hi=5.0, label="Gain (rendezvous/goto)", step=0.1, frame="gain",
                        error=BehaviourError)
    formation_edge: float = param(0.4, unit="m", lo=0.2, hi=1.0, label="Formation edge (m)", step=0.05,
                                  frame="formation_edge", error=BehaviourError)
    formation_gain: float = param(10.0, unit="1/(m² s)", lo=0.5, hi=50.0, frame="formation_gain",
                                  error=BehaviourError)
    goals: tuple[tuple[float, float], ...] | None = param(None, unit="m", error=BehaviourError)
    goal_centre: tuple[float, float] | None = param(None, unit="m", error=BehaviourError)

    def __post_init__(self) -> None:
        check_params(self)
        if self.goal_centre is not None:
            c = np.asarray(self.goal_centre, dtype=float)
            if c.shape != (2,) or not np.all(np.isfinite(c)):
                raise BehaviourError(f"goal_centre must be a finite (x, y) in m, got {self.goal_centre!r}")
        if self.goals is not None:
            g = np.asarray(self.goals, dtype=float)
            if g.ndim != 2 or g.shape[1] != 2 or not np.all(np.isfinite(g)):
                raise BehaviourError(f"goals must be a list of finite [x, y] pairs, got shape {g.shape}")


@dataclass(frozen=True)
class SafetyParams:
    """The barrier filter as the operator sets it (REFERENCE.md §3: rps's D_s = 0.17 m, γ = 100, cubic κ);
    ``mode``: "auto" is distributed above 200 robots, "anytime" the optimum within the per-tick work budget else the
    distributed answer (``swarmdeck.safety``)."""

    enabled: bool = param(True, label="Barrier on", frame="safety_enabled")
    safety_distance: float = param(SAFETY_DISTANCE, unit="m", lo=ROBOT_DIAMETER, hi=0.4, label="D_s (m)", step=0.01,
                                   frame="safety_distance", shown="safety_distance (D_s)")
    gamma: float = param(100.0, lo=1.0, hi=1000.0, label="γ", step=1.0, frame="gamma")
    class_k: str = param("cubic", choices=("cubic", "linear"), label="κ(h)", frame="class_k")
    mode: str = param("auto", choices=("centralised", "distributed", "anytime", "auto"), frame="barrier_mode")

    def __post_init__(self) -> None:
        check_params(self)


@dataclass(frozen=True)
class DensityParams:
    """The console's density: an optional circling bump (REFERENCE.md §5 S1: 0.6 m, 20 s, σ 0.4 m,
    weight 1, floor 0.05) and the σ and weight of new bumps painted in the browser."""

    moving: bool = param(True, label="Circling bump", frame="moving_density")
    radius: float = param(0.6, unit="m", lo=0.0)
    period: float = param(20.0, unit="s", lo=0.0, lo_open=True)
    sigma: float = param(0.4, unit="m", lo=0.0, lo_open=True)
    weight: float = param(1.0, lo=0.0)
    floor: float = param(0.05, lo=0.0, lo_open=True)
    bump_sigma: float = param(0.25, unit="m", lo=0.05, hi=1.0, label="σ (m)", step=0.01)
    bump_weight: float = param(1.0, lo=0.0, hi=5.0, label="Weight", step=0.1)

    def __post_init__(self) -> None:
        s1_density(self.radius, self.period, self.sigma, self.weight, self.floor)  # its own messages first
        if not in_range(self.floor, 0.0, lo_open=True):
            raise ValueError(f"density floor must be > 0 (keeps every cell's mass positive), got {self.floor!r}")
        check_params(self)


@dataclass(frozen=True)
class LoopConfig:
    """Everything the loop starts with (``[console]`` in the config file). Units m, s."""

    # no upper bound on robots: how many fit depends on the arena (the initial layout names the maximum)
    n_robots: int = param(12, lo=1, integer=True, toml="robots")
    dt: float = param(CONTROL_PERIOD, unit="s", lo=0.005, hi=0.5)
    bounds: Bounds = param(DEFAULT_BOUNDS, unit="m")
    seed: int | None = param(None)
    behaviour: str = param("coverage")
    max_speed: float = param(0.2, unit="m/s", lo=0.0, hi=1.0, lo_open=True, frame="max_speed")
    behaviour_params: BehaviourParams = field(default_factory=BehaviourParams)
    safety: SafetyParams = field(default_factory=SafetyParams)
    density: DensityParams = field(default_factory=DensityParams)
    script_budget: float | None = param(None, unit="s", lo=0.0, hi=0.5, lo_open=True)
    # the robots' sensors in every Frame (issue 28.1: Robotarium 2.0's ToF sensors, encoders, IMU and LEDs;
    # swarmdeck.sensing), seeded from `seed`; robots whose firmware reports readings give theirs
    sensors: bool = param(False)
    # coverage two ticks behind on two worker threads (console/runtime/coverage_worker.py): "auto" = from 2000 robots
    coverage_worker: str = param("auto", choices=("auto", "on", "off"))
    # line-segment obstacles on the floor ([arena] obstacles; core.obstacles): static for the run, not an operator knob
    obstacles: Obstacles | None = None

    @property
    def script_budget_s(self) -> float:
        """How long a tick waits for a ``script:`` behaviour, s: ``script_budget``, or half of ``dt``
        (the other half is the loop's own work). A script that takes longer is abandoned for the tick
        (robots stopped; :mod:`swarmdeck.console.runtime.deadline`)."""
        return 0.5 * self.dt if self.script_budget is None else float(self.script_budget)

    def __post_init__(self) -> None:
        check_params(self)
        arena = ArenaConfig(bounds=self.bounds, dt=self.dt, obstacles=self.obstacles)  # validates bounds, obstacles
        object.__setattr__(self, "obstacles", arena.obstacles)


@dataclass(frozen=True)
class ProjectorParams:
    """What the overhead projector draws on the floor (``swarmdeck console --projector``; the console panel's
    "Projector" folder): one switch per layer of the picture, the opacity of the whole image (0: dark, 1: full
    brightness) and the blackout switch (the projector shows black). Not part of the Frame: the projector
    only shows the run, it does not change it."""

    density: bool = param(True, label="Density")
    cells: bool = param(True, label="Voronoi cells")
    centroids: bool = param(True, label="Centroids")
    goals: bool = param(True, label="Goals")
    halos: bool = param(True, label="Robot halos")
    safety: bool = param(False, label="Safety discs")
    graph: bool = param(True, label="Communication graph")
    annotations: bool = param(True, label="Annotations")
    opacity: float = param(1.0, lo=0.0, hi=1.0, label="Brightness", step=0.05)
    blackout: bool = param(False, label="Blackout")

    def __post_init__(self) -> None:
        check_params(self)


#: The groups whose parameters a Frame carries, in ``Frame.params`` order.
FRAME_GROUPS: tuple[type, ...] = (BehaviourParams, SafetyParams, DensityParams, LoopConfig)


def frame_params(*groups: Any) -> dict[str, Any]:
    """``Frame.params`` of parameter objects (one per class of :data:`FRAME_GROUPS`, in that order):
    each declared ``frame`` key with its value."""
    return {s.frame: getattr(g, name) for g in groups for name, s in specs(g) if s.frame is not None}


def frame_keys(cls: type) -> dict[str, str]:
    """``Frame.params`` key -> field name of the parameters of ``cls`` a Frame carries."""
    return {s.frame: name for name, s in specs(cls) if s.frame is not None}


# ---------------------------------------------------------------------------------------------- (de)serialising
def _plain(value: Any) -> Any:
    if isinstance(value, Obstacles):
        return value.to_list()
    if isinstance(value, tuple):
        return [_plain(v) for v in value]
    return value


def to_dict(obj: Any) -> dict[str, Any]:
    """A params dataclass (nested ones too) as JSON-able dicts; tuples become lists (inverse: :func:`from_dict`)."""
    out: dict[str, Any] = {}
    for f in dataclasses.fields(obj):
        v = getattr(obj, f.name)
        out[f.name] = to_dict(v) if dataclasses.is_dataclass(v) and not isinstance(v, Obstacles) else _plain(v)
    return out


def from_dict(cls: type[T], d: Mapping[str, Any]) -> T:
    """Rebuild ``cls`` from :func:`to_dict` output: nested params classes by their field type, lists as
    tuples; the class's own checks apply. TypeError for unknown keys."""
    convert = converters(cls)
    nested = {f.name: f.default_factory for f in dataclasses.fields(cls)  # type: ignore[arg-type]
              if f.default_factory is not dataclasses.MISSING and dataclasses.is_dataclass(f.default_factory)}
    kw: dict[str, Any] = {}
    for key, value in dict(d).items():
        if key in nested:
            kw[key] = from_dict(nested[key], value or {})  # type: ignore[arg-type]
        else:
            kw[key] = convert[key](value) if key in convert else value
    return cls(**kw)
