"""The immutable ``Frame``: everything one control tick sensed, decided and sent (DESIGN.md "One tick").

The control loop produces one :class:`Frame` per tick; the viser scene draws
Frames, the recorder writes them and the player reads them back and hands them
to the same drawing code. A Frame never changes after it is built: it is a
frozen dataclass and every numpy array in it is read-only.

Recording format
----------------
:meth:`Frame.to_dict` gives plain JSON-able data (dicts, lists, str, int,
float, bool, None) and :meth:`Frame.from_dict` restores an equal Frame, so
``Frame.from_dict(json.loads(json.dumps(f.to_dict())))`` round-trips exactly
(Python's float repr is exact). Non-finite floats are written as the strings
``"NaN"``, ``"Infinity"``, ``"-Infinity"`` so the output is strict JSON. Keys
(version ``FRAME_FORMAT``, units m, s, rad; N robots, E Voronoi edges, K
active barrier pairs, B density bumps, C contacts)::

    format        int, FRAME_FORMAT
    tick          int, tick index from 0
    time          float s, the loop's clock (virtual under tick(), monotonic when threaded)
    run_time      float s, behaviour time: advances by dt only on ticks that ran (not paused/stopped);
                  time-varying densities are evaluated at run_time
    dt            float s, control period
    bounds        [x_min, x_max, y_min, y_max] m
    lookahead     float m, ℓ of the controlled (look-ahead) points
    ids           (N,) int robot ids
    poses         (N,3) [x, y, θ]
    seen          (N,) bool, pose is fresh this tick (always true in simulation)
    nominal       (N,2) m/s single-integrator command of the behaviour (look-ahead points)
    safe          (N,2) m/s command after the safety filter (zeros when stopped)
    v, w          (N,) m/s, rad/s unicycle command sent to the robots
    barrier       null | {enabled, ok, status, solve_time_s, n_constraints, n_active,
                          active_pairs (K,2) int, active_h (K,) m², min_distance m,
                          min_wall_clearance m, intervention (N,) m/s, nominal_was_safe,
                          safety_distance m}
    coverage      null | {centroids (N,2), masses (N,), edges (E,2,2), neighbours (E,2) int,
                          cost_H, mean_centroid_distance m, packing_warning str|null,
                          cell_vertices (V,2), cell_offsets (N+1,) int: cell i is
                          cell_vertices[cell_offsets[i]:cell_offsets[i+1]]}
    density       null | GaussianMixture.to_dict() (floor, mu, sigma|cov, weight, *_dot)
    contacts      {sources [C] str, ids (C,) int, positions (C,2), velocities (C,2)}
    behaviour     str  ("coverage", "rendezvous", "formation", "goto", "script:PATH")
    run_state     "running" | "paused" | "estop"
    params        {name: number|str|bool} operator parameters in force (``params.frame_params``: every
                  parameter declared with a ``frame`` key in console/runtime/params.py), goals for goto
    events        [str] messages raised during this tick
    alerts        [str] conditions in force (script failing, filter failed, …)
    health        {source name: str} input sources / transport and their state
    timing        {stage: float s} sense, inputs, control, safety, actuate, total
    image_ref     str | null, reference to the camera image of this tick
    is_virtual    (N,) bool, robot simulated beside the physical ones (``devices.virtual_robots``);
                  written only when some robot is virtual, absent (all physical) in older recordings
    battery       (N,) V battery voltage (NaN: unknown); written only when some robot reports one
    charging      (N,) bool, robot on a charger; written only when some robot is charging
    sensors       what the robots sensed (ToF distances, LEDs, encoders, IMU): ``SensorsFrame``
                  (console/runtime/sensors_frame.py has its layout); written only when present
    obstacles     [[[x0, y0], [x1, y1]], ...] m, the line-segment obstacles on the floor
                  (``core.obstacles.Obstacles``); written only when there are some (the recording codec
                  writes them in keyframes and when they change, :func:`obstacles_dict`)
    network       {links (E,2) int, rate (E,) messages/s}: the robots' communication graph this tick
                  (console/runtime/network_frame.py); written only when present (a decentralised run)
    annotations   what the experiment drew this tick (``swarmdeck.core.annotations.Annotations.to_dict``:
                  kinds, offsets, vertices m, sizes m, colors RGBA, filled, texts); written only when it drew
                  something, absent (nothing drawn) in older recordings

The browser GUI's editing state (bump handles, plots) is not part of a Frame;
the density the loop used is.
"""
from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from types import MappingProxyType
from typing import Any, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.console.runtime.network_frame import NetworkFrame
from swarmdeck.console.runtime.sensors_frame import SensorsFrame
from swarmdeck.core.annotations import Annotations
from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds
from swarmdeck.core.constants import CONTROL_PERIOD, LOOKAHEAD, SAFETY_DISTANCE
from swarmdeck.core.kinematics import lookahead_points
from swarmdeck.core.obstacles import Obstacles
from swarmdeck.coverage.cells import CellPolygons
from swarmdeck.coverage.density import GaussianMixture
from swarmdeck.coverage.geometry import GeometryConfig

FRAME_FORMAT = 1
RUN_STATES = ("running", "paused", "estop")

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
_Scalar = TypeVar("_Scalar", bound=np.generic)


def filled(array: NDArray[_Scalar] | None) -> NDArray[_Scalar]:
    """A Frame's per-robot array that its constructor takes as optional (``seen``, ``is_virtual``, ``battery``,
    ``charging``: None means the default) and ``__post_init__`` always fills, ``(N,)``, as the type checker
    should see it on a built Frame. ValueError for None (a Frame whose ``__post_init__`` did not run)."""
    if array is None:
        raise ValueError("a Frame's per-robot array is None: the Frame was not built through its constructor")
    return array


# ---------------------------------------------------------------------------- JSON helpers
def _enc_float(x: float) -> float | str:
    x = float(x)
    if math.isfinite(x):
        return x
    return "NaN" if math.isnan(x) else ("Infinity" if x > 0 else "-Infinity")


def _dec_float(x: Any) -> float:
    if isinstance(x, str):
        if x not in ("NaN", "Infinity", "-Infinity"):
            raise ValueError(f"expected a number or 'NaN'/'Infinity'/'-Infinity', got {x!r}")
        return float(x.replace("Infinity", "inf"))
    return float(x)


def _enc_array(a: NDArray[Any]) -> list:
    if a.dtype.kind == "f" and not np.all(np.isfinite(a)):
        obj = a.astype(object)
        bad = ~np.isfinite(a)
        obj[bad] = [_enc_float(v) for v in a[bad]]
        return obj.tolist()
    return a.tolist()


def _dec_array(data: Any, dtype: type, shape_tail: tuple[int, ...], name: str) -> NDArray[Any]:
    if dtype is float:
        arr = np.asarray(data, dtype=object) if data is not None else np.empty((0,) + shape_tail)
        if arr.dtype == object:
            flat = [_dec_float(v) for v in arr.reshape(-1)]
            arr = np.asarray(flat, dtype=float).reshape(arr.shape)
        arr = arr.astype(float)
    else:
        arr = np.asarray(data, dtype=dtype)
    if arr.size == 0:
        arr = arr.reshape((0,) + shape_tail)
    if arr.shape[1:] != shape_tail:
        raise ValueError(f"frame field {name!r} must have shape (n,{','.join(map(str, shape_tail))}), got {arr.shape}")
    return arr


def _ro(a: ArrayLike, dtype: type, shape_tail: tuple[int, ...], name: str) -> NDArray[Any]:
    """A read-only copy of ``a`` with the given dtype and trailing shape."""
    arr: NDArray[Any] = np.array(a, dtype=dtype, copy=True)
    if arr.size == 0:
        arr = arr.reshape((0,) + shape_tail)
    if arr.ndim != 1 + len(shape_tail) or arr.shape[1:] != shape_tail:
        want = "(n" + "".join(f", {s}" for s in shape_tail) + ")"
        raise ValueError(f"frame field {name!r} must have shape {want}, got {arr.shape}")
    arr.setflags(write=False)
    return arr


def _freeze_map(m: Mapping[str, Any] | None) -> Mapping[str, Any]:
    return MappingProxyType(dict(m or {}))


def obstacles_of(value: Any) -> Obstacles | None:
    """A Frame's ``obstacles`` from what was given (Obstacles, an (M, 2, 2) array, nested lists, None):
    None when there are none; ValueError naming the segment for a malformed one."""
    if value is None:
        return None
    return Obstacles.of(value) or None


def obstacles_dict(obstacles: Obstacles | None) -> dict[str, Any]:
    """``{"obstacles": [[[x0, y0], [x1, y1]], ...]}`` when there are obstacles, else ``{}`` (older readers and
    recordings without obstacles read as none)."""
    return {} if obstacles is None else {"obstacles": obstacles.to_list()}


def _set(obj: Any, name: str, value: Any) -> None:
    object.__setattr__(obj, name, value)


# ---------------------------------------------------------------------------- parts
@dataclass(frozen=True, eq=False)
class BarrierFrame:
    """The safety filter's report for one tick (see ``swarmdeck.safety.BarrierDiagnostics``).

    ``active_pairs`` (K, 2) robot index pairs whose pair constraint was active,
    ``active_h`` (K,) their barrier values h = ‖p_i − p_j‖² − D_s² (m²),
    ``intervention`` (N,) ‖safe_i − nominal_i‖ (m/s). ``enabled`` False means the
    operator switched the filter off (safe = nominal).
    """

    enabled: bool = True
    ok: bool = True
    status: str = "ok"
    solve_time_s: float = 0.0
    n_constraints: int = 0
    n_active: int = 0
    active_pairs: IntArray = field(default_factory=lambda: np.empty((0, 2), dtype=np.int64))
    active_h: FloatArray = field(default_factory=lambda: np.empty(0))
    min_distance: float = math.inf
    min_wall_clearance: float = math.inf
    intervention: FloatArray = field(default_factory=lambda: np.empty(0))
    nominal_was_safe: bool = True
    safety_distance: float = SAFETY_DISTANCE

    def __post_init__(self) -> None:
        _set(self, "active_pairs", _ro(self.active_pairs, np.int64, (2,), "barrier.active_pairs"))
        _set(self, "active_h", _ro(self.active_h, float, (), "barrier.active_h"))
        _set(self, "intervention", _ro(self.intervention, float, (), "barrier.intervention"))
        for name in ("solve_time_s", "min_distance", "min_wall_clearance", "safety_distance"):
            _set(self, name, float(getattr(self, name)))
        for name in ("n_constraints", "n_active"):
            _set(self, name, int(getattr(self, name)))
        for name in ("enabled", "ok", "nominal_was_safe"):
            _set(self, name, bool(getattr(self, name)))
        _set(self, "status", str(self.status))

    @classmethod
    def from_diagnostics(cls, diag: Any, n: int, safety_distance: float, enabled: bool = True) -> BarrierFrame:
        """Build from a ``BarrierDiagnostics``-like object (attributes per the safety contract)."""

        def get(key: str, default: Any) -> Any:
            return getattr(diag, key, default)

        inter = get("intervention", None)
        return cls(
            enabled=enabled,
            ok=get("ok", True),
            status=get("status", "ok"),
            solve_time_s=get("solve_time_s", 0.0),
            n_constraints=get("n_constraints", 0),
            n_active=get("n_active", 0),
            active_pairs=get("active_pairs", np.empty((0, 2), dtype=np.int64)),
            active_h=get("active_h", np.empty(0)),
            min_distance=get("min_distance", math.inf),
            min_wall_clearance=get("min_wall_clearance", math.inf),
            intervention=np.zeros(n) if inter is None else inter,
            nominal_was_safe=get("nominal_was_safe", True),
            safety_distance=safety_distance,
        )

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for f in fields(self):
            v = getattr(self, f.name)
            out[f.name] = _enc_array(v) if isinstance(v, np.ndarray) else (_enc_float(v) if isinstance(v, float) else v)
        return out

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> BarrierFrame:
        return cls(
            enabled=d["enabled"], ok=d["ok"], status=d["status"], solve_time_s=_dec_float(d["solve_time_s"]),
            n_constraints=d["n_constraints"], n_active=d["n_active"],
            active_pairs=_dec_array(d["active_pairs"], np.int64, (2,), "barrier.active_pairs"),
            active_h=_dec_array(d["active_h"], float, (), "barrier.active_h"),
            min_distance=_dec_float(d["min_distance"]), min_wall_clearance=_dec_float(d["min_wall_clearance"]),
            intervention=_dec_array(d["intervention"], float, (), "barrier.intervention"),
            nominal_was_safe=d["nominal_was_safe"], safety_distance=_dec_float(d["safety_distance"]),
        )


def _flat_cells(cells: Any) -> tuple[FloatArray, IntArray]:
    """Polygons (V_i, 2) m → their concatenated vertices (V, 2) and offsets (N + 1,) (a flat
    ``CellPolygons`` is taken as it is: no copy)."""
    flat = CellPolygons.from_list(cells if cells is not None else [])
    return flat.vertices, flat.offsets


@dataclass(frozen=True, eq=False)
class CoverageFrame:
    """Coverage state of one tick (see ``swarmdeck.coverage.CoverageState``).

    centroids (N, 2) m, masses (N,), edges (E, 2, 2) Voronoi edge segments m,
    neighbours (E, 2) robot index pairs, cost_H the locational cost,
    mean_centroid_distance mean ‖p_i − c_i‖ m, cells as concatenated vertices
    (V, 2) with offsets (N + 1,); geometry_config: what the cells and moments were computed with
    (``swarmdeck.coverage.GeometryConfig``; None: the defaults on the frame's bounds).
    """

    centroids: FloatArray
    masses: FloatArray
    edges: FloatArray
    neighbours: IntArray
    cost_H: float
    mean_centroid_distance: float
    packing_warning: str | None = None
    cell_vertices: FloatArray = field(default_factory=lambda: np.empty((0, 2)))
    cell_offsets: IntArray = field(default_factory=lambda: np.zeros(1, dtype=np.int64))
    geometry_config: GeometryConfig | None = None

    def __post_init__(self) -> None:
        _set(self, "centroids", _ro(self.centroids, float, (2,), "coverage.centroids"))
        _set(self, "masses", _ro(self.masses, float, (), "coverage.masses"))
        _set(self, "edges", _ro(self.edges, float, (2, 2), "coverage.edges"))
        _set(self, "neighbours", _ro(self.neighbours, np.int64, (2,), "coverage.neighbours"))
        _set(self, "cell_vertices", _ro(self.cell_vertices, float, (2,), "coverage.cell_vertices"))
        _set(self, "cell_offsets", _ro(self.cell_offsets, np.int64, (), "coverage.cell_offsets"))
        _set(self, "cost_H", float(self.cost_H))
        _set(self, "mean_centroid_distance", float(self.mean_centroid_distance))
        if self.packing_warning is not None:
            _set(self, "packing_warning", str(self.packing_warning))

    @classmethod
    def from_state(cls, state: Any) -> CoverageFrame:
        """Build from a ``CoverageState``-like object (attributes per the coverage contract)."""
        verts, offsets = _flat_cells(getattr(state, "cells", None))
        return cls(
            centroids=state.centroids, masses=state.masses, edges=state.edges,
            neighbours=getattr(state, "neighbours", np.empty((0, 2), dtype=np.int64)),
            cost_H=state.cost_H, mean_centroid_distance=state.mean_centroid_distance,
            packing_warning=getattr(state, "packing_warning", None),
            cell_vertices=verts, cell_offsets=offsets, geometry_config=getattr(state, "geometry_config", None),
        )

    @classmethod
    def from_geometry(cls, geometry: Any, cost_H: float, mean_centroid_distance: float,
                      packing_warning: str | None = None) -> CoverageFrame:
        """Build from a ``swarmdeck.coverage.CoverageGeometry`` that has a diagram (a recorded frame's
        cells, derived again) and the tick's scalars."""
        verts, offsets = _flat_cells(geometry.cell_polygons())
        return cls(centroids=geometry.centroids, masses=geometry.masses, edges=geometry.edges,
                   neighbours=geometry.neighbours, cost_H=cost_H, mean_centroid_distance=mean_centroid_distance,
                   packing_warning=packing_warning, cell_vertices=verts, cell_offsets=offsets,
                   geometry_config=geometry.config)

    def cells(self) -> list[FloatArray]:
        """The cell polygons as a list of (V_i, 2) arrays (views, read-only)."""
        o = self.cell_offsets
        return [self.cell_vertices[o[i]:o[i + 1]] for i in range(len(o) - 1)]

    def to_dict(self) -> dict[str, Any]:
        return {
            "centroids": _enc_array(self.centroids), "masses": _enc_array(self.masses),
            "edges": _enc_array(self.edges), "neighbours": self.neighbours.tolist(),
            "cost_H": _enc_float(self.cost_H), "mean_centroid_distance": _enc_float(self.mean_centroid_distance),
            "packing_warning": self.packing_warning,
            "cell_vertices": _enc_array(self.cell_vertices), "cell_offsets": self.cell_offsets.tolist(),
        }

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> CoverageFrame:
        return cls(
            centroids=_dec_array(d["centroids"], float, (2,), "coverage.centroids"),
            masses=_dec_array(d["masses"], float, (), "coverage.masses"),
            edges=_dec_array(d["edges"], float, (2, 2), "coverage.edges"),
            neighbours=_dec_array(d["neighbours"], np.int64, (2,), "coverage.neighbours"),
            cost_H=_dec_float(d["cost_H"]), mean_centroid_distance=_dec_float(d["mean_centroid_distance"]),
            packing_warning=d.get("packing_warning"),
            cell_vertices=_dec_array(d.get("cell_vertices", []), float, (2,), "coverage.cell_vertices"),
            cell_offsets=_dec_array(d.get("cell_offsets", [0]), np.int64, (), "coverage.cell_offsets"),
        )


@dataclass(frozen=True, eq=False)
class ContactsFrame:
    """Input contacts of one tick: sources [C] str, ids (C,), positions (C, 2) m, velocities (C, 2) m/s."""

    sources: tuple[str, ...] = ()
    ids: IntArray = field(default_factory=lambda: np.empty(0, dtype=np.int64))
    positions: FloatArray = field(default_factory=lambda: np.empty((0, 2)))
    velocities: FloatArray = field(default_factory=lambda: np.empty((0, 2)))

    def __post_init__(self) -> None:
        _set(self, "sources", tuple(str(s) for s in self.sources))
        _set(self, "ids", _ro(self.ids, np.int64, (), "contacts.ids"))
        _set(self, "positions", _ro(self.positions, float, (2,), "contacts.positions"))
        _set(self, "velocities", _ro(self.velocities, float, (2,), "contacts.velocities"))
        c = len(self.ids)
        if len(self.sources) != c or len(self.positions) != c or len(self.velocities) != c:
            raise ValueError("contacts: sources, ids, positions and velocities must have the same length")

    @classmethod
    def from_contacts(cls, contacts: Any) -> ContactsFrame:
        """From an iterable of ``Contact``-like objects (source, id, position, velocity)."""
        cs = list(contacts or [])
        if not cs:
            return cls()
        return cls(
            sources=tuple(str(getattr(c, "source", "")) for c in cs),
            ids=np.array([int(getattr(c, "id", 0)) for c in cs], dtype=np.int64),
            positions=np.array([np.asarray(c.position, dtype=float)[:2] for c in cs], dtype=float),
            velocities=np.array([np.asarray(getattr(c, "velocity", (0.0, 0.0)), dtype=float)[:2] for c in cs], dtype=float),
        )

    def __len__(self) -> int:
        return len(self.ids)

    def to_dict(self) -> dict[str, Any]:
        return {"sources": list(self.sources), "ids": self.ids.tolist(),
                "positions": _enc_array(self.positions), "velocities": _enc_array(self.velocities)}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> ContactsFrame:
        return cls(sources=tuple(d["sources"]), ids=_dec_array(d["ids"], np.int64, (), "contacts.ids"),
                   positions=_dec_array(d["positions"], float, (2,), "contacts.positions"),
                   velocities=_dec_array(d["velocities"], float, (2,), "contacts.velocities"))


def _enc_map(m: Mapping[str, Any]) -> dict[str, Any]:
    return {k: (_enc_float(v) if isinstance(v, float) else v) for k, v in m.items()}


# ---------------------------------------------------------------------------- the Frame
@dataclass(frozen=True, eq=False)
class Frame:
    """One control tick. See the module docstring for the fields, units and the recording format."""

    tick: int
    time: float
    poses: FloatArray
    ids: IntArray
    nominal: FloatArray
    safe: FloatArray
    v: FloatArray
    w: FloatArray
    dt: float = CONTROL_PERIOD
    run_time: float = 0.0
    bounds: Bounds = DEFAULT_BOUNDS
    lookahead: float = LOOKAHEAD
    seen: NDArray[np.bool_] | None = None
    barrier: BarrierFrame | None = None
    coverage: CoverageFrame | None = None
    density: GaussianMixture | None = None
    contacts: ContactsFrame = field(default_factory=ContactsFrame)
    behaviour: str = "coverage"
    run_state: str = "running"
    params: Mapping[str, Any] = field(default_factory=dict)
    events: tuple[str, ...] = ()
    alerts: tuple[str, ...] = ()
    health: Mapping[str, str] = field(default_factory=dict)
    timing: Mapping[str, float] = field(default_factory=dict)
    image_ref: str | None = None
    is_virtual: NDArray[np.bool_] | None = None
    battery: FloatArray | None = None
    charging: NDArray[np.bool_] | None = None
    sensors: SensorsFrame | None = None
    obstacles: Obstacles | None = None
    network: NetworkFrame | None = None
    annotations: Annotations | None = None

    def __post_init__(self) -> None:
        _set(self, "obstacles", obstacles_of(self.obstacles))
        _set(self, "tick", int(self.tick))
        _set(self, "time", float(self.time))
        _set(self, "dt", float(self.dt))
        _set(self, "run_time", float(self.run_time))
        _set(self, "lookahead", float(self.lookahead))
        _set(self, "bounds", tuple(float(b) for b in self.bounds))
        if len(self.bounds) != 4:
            raise ValueError(f"frame bounds must be (x_min, x_max, y_min, y_max), got {self.bounds}")
        poses = _ro(self.poses, float, (3,), "poses")
        n = len(poses)
        _set(self, "poses", poses)
        for name, tail, dt in (("ids", (), np.int64), ("nominal", (2,), float), ("safe", (2,), float),
                               ("v", (), float), ("w", (), float)):
            arr = _ro(getattr(self, name), dt, tail, name)
            if len(arr) != n:
                raise ValueError(f"frame field {name!r} has {len(arr)} rows but there are {n} poses")
            _set(self, name, arr)
        seen = np.ones(n, dtype=bool) if self.seen is None else self.seen
        _set(self, "seen", _ro(seen, bool, (), "seen"))
        for name, dt, default in (("is_virtual", bool, False), ("battery", float, math.nan), ("charging", bool, False)):
            value = getattr(self, name)
            arr = _ro(np.full(n, default, dtype=dt) if value is None else value, dt, (), name)
            if len(arr) != n:
                raise ValueError(f"frame field {name!r} has {len(arr)} rows but there are {n} poses")
            _set(self, name, arr)
        if self.sensors is not None:
            if not isinstance(self.sensors, SensorsFrame):
                raise ValueError(f"frame sensors must be a SensorsFrame, got {type(self.sensors).__name__}")
            rows = self.sensors.n_rows()
            if rows is not None and rows != n:
                raise ValueError(f"frame field 'sensors' has {rows} rows but there are {n} poses")
        if self.network is not None:
            if not isinstance(self.network, NetworkFrame):
                raise ValueError(f"frame network must be a NetworkFrame, got {type(self.network).__name__}")
            self.network.check_robots(n)
        if self.run_state not in RUN_STATES:
            raise ValueError(f"run_state must be one of {RUN_STATES}, got {self.run_state!r}")
        if self.density is not None and not isinstance(self.density, GaussianMixture):
            raise ValueError(f"frame density must be a GaussianMixture snapshot, got {type(self.density).__name__}")
        _set(self, "behaviour", str(self.behaviour))
        _set(self, "events", tuple(str(e) for e in self.events))
        _set(self, "alerts", tuple(str(e) for e in self.alerts))
        _set(self, "params", _freeze_map(self.params))
        _set(self, "health", _freeze_map({str(k): str(v) for k, v in dict(self.health).items()}))
        _set(self, "timing", _freeze_map({str(k): float(v) for k, v in dict(self.timing).items()}))
        if self.annotations is not None and not isinstance(self.annotations, Annotations):
            raise ValueError(f"frame annotations must be Annotations, got {type(self.annotations).__name__}")

    @property
    def n(self) -> int:
        """Number of robots N."""
        return int(self.poses.shape[0])

    @property
    def points(self) -> FloatArray:
        """Controlled (look-ahead) points ``(N, 2)``: p = (x + ℓ cos θ, y + ℓ sin θ)."""
        return lookahead_points(self.poses, self.lookahead)

    @property
    def stopped(self) -> bool:
        """True when every robot is commanded to stand still."""
        return bool(not np.any(self.v) and not np.any(self.w))

    def to_dict(self) -> dict[str, Any]:
        """JSON-able dict: the recording format (module docstring)."""
        return {
            "format": FRAME_FORMAT,
            "tick": self.tick,
            "time": _enc_float(self.time),
            "dt": _enc_float(self.dt),
            "run_time": _enc_float(self.run_time),
            "bounds": [_enc_float(b) for b in self.bounds],
            "lookahead": _enc_float(self.lookahead),
            "ids": self.ids.tolist(),
            "poses": _enc_array(self.poses),
            "seen": filled(self.seen).tolist(),
            "nominal": _enc_array(self.nominal),
            "safe": _enc_array(self.safe),
            "v": _enc_array(self.v),
            "w": _enc_array(self.w),
            "barrier": None if self.barrier is None else self.barrier.to_dict(),
            "coverage": None if self.coverage is None else self.coverage.to_dict(),
            "density": None if self.density is None else self.density.to_dict(),
            "contacts": self.contacts.to_dict(),
            "behaviour": self.behaviour,
            "run_state": self.run_state,
            "params": _enc_map(self.params),
            "events": list(self.events),
            "alerts": list(self.alerts),
            "health": dict(self.health),
            "timing": _enc_map(self.timing),
            "image_ref": self.image_ref,
            **self.fleet_dict(),
            **({} if self.sensors is None else {"sensors": self.sensors.to_dict(_enc_array)}),
            **obstacles_dict(self.obstacles),
            **({} if self.network is None else {"network": self.network.to_dict()}),
            **self.annotations_dict(),
        }

    def annotations_dict(self) -> dict[str, Any]:
        """``{"annotations": ...}`` when the experiment drew something this tick, else ``{}`` (older readers and
        recordings without it read as nothing drawn)."""
        return {} if self.annotations is None or not len(self.annotations) else {
            "annotations": self.annotations.to_dict()}

    def fleet_dict(self) -> dict[str, Any]:
        """``is_virtual``, ``battery``, ``charging`` as JSON lists, each only when it says something
        (some robot virtual, some battery known, some robot charging): older readers and recordings
        without them read as all physical, battery unknown, not charging."""
        out: dict[str, Any] = {}
        is_virtual, battery, charging = filled(self.is_virtual), filled(self.battery), filled(self.charging)
        if is_virtual.any():
            out["is_virtual"] = is_virtual.tolist()
        if np.isfinite(battery).any():
            out["battery"] = _enc_array(battery)
        if charging.any():
            out["charging"] = charging.tolist()
        return out

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> Frame:
        """Inverse of :meth:`to_dict`; raises ValueError naming the field for malformed data."""
        if not isinstance(d, Mapping):
            raise ValueError(f"a frame must be a dict, got {type(d).__name__}")
        fmt = d.get("format")
        if fmt != FRAME_FORMAT:
            raise ValueError(f"unsupported frame format {fmt!r} (this swarmdeck reads format {FRAME_FORMAT})")
        try:
            params = {k: (_dec_float(v) if isinstance(v, str) and v in ("NaN", "Infinity", "-Infinity") else v)
                      for k, v in d.get("params", {}).items()}
            return cls(
                tick=d["tick"], time=_dec_float(d["time"]), dt=_dec_float(d["dt"]),
                run_time=_dec_float(d.get("run_time", 0.0)),
                bounds=tuple(_dec_float(b) for b in d["bounds"]), lookahead=_dec_float(d["lookahead"]),
                ids=_dec_array(d["ids"], np.int64, (), "ids"),
                poses=_dec_array(d["poses"], float, (3,), "poses"),
                seen=_dec_array(d["seen"], bool, (), "seen"),
                nominal=_dec_array(d["nominal"], float, (2,), "nominal"),
                safe=_dec_array(d["safe"], float, (2,), "safe"),
                v=_dec_array(d["v"], float, (), "v"), w=_dec_array(d["w"], float, (), "w"),
                barrier=None if d.get("barrier") is None else BarrierFrame.from_dict(d["barrier"]),
                coverage=None if d.get("coverage") is None else CoverageFrame.from_dict(d["coverage"]),
                density=None if d.get("density") is None else GaussianMixture.from_dict(d["density"]),
                contacts=ContactsFrame.from_dict(d.get("contacts") or ContactsFrame().to_dict()),
                behaviour=d.get("behaviour", ""), run_state=d.get("run_state", "running"),
                params=params, events=tuple(d.get("events", ())), alerts=tuple(d.get("alerts", ())),
                health=d.get("health", {}),
                timing={k: _dec_float(v) for k, v in d.get("timing", {}).items()},
                image_ref=d.get("image_ref"),
                is_virtual=None if d.get("is_virtual") is None else _dec_array(d["is_virtual"], bool, (), "is_virtual"),
                battery=None if d.get("battery") is None else _dec_array(d["battery"], float, (), "battery"),
                charging=None if d.get("charging") is None else _dec_array(d["charging"], bool, (), "charging"),
                sensors=None if d.get("sensors") is None else SensorsFrame.from_dict(d["sensors"], _dec_array),
                obstacles=d.get("obstacles"),
                network=None if d.get("network") is None else NetworkFrame.from_dict(d["network"]),
                annotations=None if d.get("annotations") is None else Annotations.from_dict(d["annotations"]),
            )
        except KeyError as exc:
            raise ValueError(f"frame is missing field {exc.args[0]!r}") from None
