"""The coverage controller: one call per tick, positions and time in, nominal velocities out.

Pipeline (REFERENCE.md §5): pre-condition positions (clamp inside, separate near-duplicates) →
bounded Voronoi → cell integrals (m, c, ∂c/∂t, H) → Jacobian ∂c/∂p (TVD laws only) → law →
saturation to ``max_speed``. The nominal commands go to the safety filter afterwards.

Example::

    ctrl = CoverageController(CoverageConfig(law="tvd-d1"), density)
    nominal, state = ctrl(positions, t)     # (N, 2) m/s, CoverageState
"""
from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds, check_bounds
from swarmdeck.core.checks import require_in_range
from swarmdeck.core.config import from_mapping
from swarmdeck.core.constants import MAX_LINEAR_SPEED, SAFETY_DISTANCE
from swarmdeck.core.kinematics import saturate
from swarmdeck.coverage.density import Density, GaussianMixture
from swarmdeck.coverage.geometry import (
    DEFAULT_QUADRATURE,
    NUMERICAL_ERRORS,
    CoverageGeometry,
    GeometryConfig,
    geometry_diagram,
    geometry_moments,
)
from swarmdeck.coverage.jacobian import EdgeOptions, centroid_jacobian
from swarmdeck.coverage.laws import law_command, parse_law
from swarmdeck.coverage.packing import packing_warning
from swarmdeck.coverage.quadrature import QuadratureOptions

__all__ = ["CoverageConfig", "CoverageState", "CoverageController", "coverage_tick", "coverage_tick_on"]


@dataclass(frozen=True)
class CoverageConfig:
    """Coverage-controller configuration (defaults from REFERENCE.md §5).

    law: ``lloyd``, ``lloyd-ff``, ``tvd-d1`` (default), ``tvd-dk`` (with ``hops``) or
    ``tvd-d<k>``, ``tvd-c`` (only with ``allow_centralised=True``). kappa [1/s] > 0.
    max_speed [m/s] saturation per robot, ``None`` = none. bounds: arena rectangle.
    safety_distance [m]: D_s of the barrier, for the packing warning. wall_margin,
    min_separation [m]: position pre-conditioning. quadrature, edges: accuracy options.
    packing_every: recompute the packing prediction every this many ticks.
    """

    law: str = "tvd-d1"
    kappa: float = 1.0
    max_speed: float | None = MAX_LINEAR_SPEED
    bounds: Bounds = DEFAULT_BOUNDS
    hops: int = 2
    allow_centralised: bool = False
    safety_distance: float = SAFETY_DISTANCE
    wall_margin: float = 1e-6
    min_separation: float = 1e-3
    quadrature: QuadratureOptions = field(default_factory=lambda: DEFAULT_QUADRATURE)
    edges: EdgeOptions = field(default_factory=EdgeOptions)
    packing_every: int = 15

    def __post_init__(self) -> None:
        family, _ = parse_law(self.law, self.hops)
        if family == "tvd-c" and not self.allow_centralised:
            raise ValueError("law 'tvd-c' inverts I - dc/dp, which is ill-conditioned away from a "
                             "CVT (it has commanded 4e3 m/s); it is a reference only: set "
                             "allow_centralised=True to use it")
        require_in_range(self.kappa, "kappa", 0.0, lo_open=True)
        if self.max_speed is not None and not (self.max_speed > 0):
            raise ValueError(f"max_speed must be > 0 or None, got {self.max_speed!r}")
        object.__setattr__(self, "bounds", check_bounds(self.bounds))
        require_in_range(self.safety_distance, "safety_distance", 0.0, unit="m")
        _ = self.geometry  # checks wall_margin, min_separation, quadrature
        if int(self.packing_every) < 1:
            raise ValueError(f"packing_every must be >= 1, got {self.packing_every!r}")

    @property
    def geometry(self) -> GeometryConfig:
        """The part of this configuration the cells and their moments depend on
        (:func:`~swarmdeck.coverage.geometry.coverage_geometry`; stored in recordings)."""
        return GeometryConfig(bounds=self.bounds, wall_margin=self.wall_margin, min_separation=self.min_separation,
                              quadrature=self.quadrature)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> CoverageConfig:
        """Build from a plain dict (e.g. a TOML table); ``quadrature`` and ``edges`` may be
        nested tables. Raises ValueError naming unknown keys or bad values."""
        def table(typ: type, key: str) -> Callable[[Any], Any]:
            return lambda sub: from_mapping(typ, sub, f"coverage.{key}") if isinstance(sub, Mapping) else sub

        return from_mapping(cls, data, "coverage config", error=ValueError, wrap="bad {what}: {message}",
                            convert={"quadrature": table(QuadratureOptions, "quadrature"),
                                     "edges": table(EdgeOptions, "edges"), "bounds": tuple})


@dataclass(frozen=True)
class CoverageState:
    """What the console and the recorder need from one coverage tick.

    t [s]; law; status ``"ok"`` or ``"error: …"`` (then the command is zero, centroids are the
    positions, masses and costs are 0 and there are no cells: everything stays finite/JSON-able);
    positions (N, 2) the pre-conditioned positions used; centroids (N, 2) [m]; masses (N,);
    dc_dt (N, 2) [m/s]; cost_H: locational cost H = Σ_i ∫_{V_i} ‖q − p_i‖² φ;
    cost_H_normalised: H / ∫φ; mean_centroid_distance, max_centroid_distance: ‖p_i − c_i‖ [m];
    edges (E, 2, 2) shared Voronoi edge segments [m]; neighbours (E, 2) int robot pairs;
    cells: N counter-clockwise polygons (V_i, 2) [m] (a flat
    :class:`~swarmdeck.coverage.cells.CellPolygons` from a tick, read-only); packing_warning: str | None;
    repaired: robots moved by pre-conditioning; saturated: robots whose speed was limited;
    geometry_config: what the cells were computed with (recordings store it to derive them again).
    """

    t: float
    law: str
    status: str
    positions: NDArray[np.float64]
    centroids: NDArray[np.float64]
    masses: NDArray[np.float64]
    dc_dt: NDArray[np.float64]
    cost_H: float
    cost_H_normalised: float
    mean_centroid_distance: float
    max_centroid_distance: float
    edges: NDArray[np.float64]
    neighbours: NDArray[np.intp]
    cells: Sequence[NDArray[np.float64]]
    packing_warning: str | None
    repaired: int
    saturated: int
    geometry_config: GeometryConfig = field(default_factory=GeometryConfig)

    @property
    def ok(self) -> bool:
        return self.status == "ok"

    def to_dict(self) -> dict[str, Any]:
        """JSON-able form (lists of floats)."""
        return {
            "t": float(self.t), "law": self.law, "status": self.status,
            "positions": self.positions.tolist(), "centroids": self.centroids.tolist(),
            "masses": self.masses.tolist(), "dc_dt": self.dc_dt.tolist(),
            "cost_H": float(self.cost_H), "cost_H_normalised": float(self.cost_H_normalised),
            "mean_centroid_distance": float(self.mean_centroid_distance),
            "max_centroid_distance": float(self.max_centroid_distance),
            "edges": self.edges.tolist(), "neighbours": self.neighbours.tolist(),
            "cells": [c.tolist() for c in self.cells],
            "packing_warning": self.packing_warning,
            "repaired": int(self.repaired), "saturated": int(self.saturated),
        }



def coverage_tick(positions: ArrayLike, density: GaussianMixture, config: CoverageConfig,
                  t: float = 0.0, packing: str | None = None
                  ) -> tuple[NDArray[np.float64], CoverageState, sp.csr_array | None]:
    """One tick as a pure function: (nominal (N, 2) m/s, state, ∂c/∂p or None).

    Raises ValueError for malformed positions; numerical failures (a degenerate diagram, a
    singular TVD-C system) give zero commands and ``state.status = "error: …"``.
    """
    if not isinstance(density, GaussianMixture):
        raise TypeError(f"a density snapshot must be a GaussianMixture, got {type(density).__name__}")
    return coverage_tick_on(geometry_diagram(positions, config.geometry), density, config, t, packing)


def coverage_tick_on(diagram: CoverageGeometry, density: GaussianMixture, config: CoverageConfig,
                     t: float = 0.0, packing: str | None = None
                     ) -> tuple[NDArray[np.float64], CoverageState, sp.csr_array | None]:
    """:func:`coverage_tick` from the tick's diagram already built (``geometry_diagram(positions,
    config.geometry)``): the same result, bit for bit."""
    if not isinstance(density, GaussianMixture):
        raise TypeError(f"a density snapshot must be a GaussianMixture, got {type(density).__name__}")
    geo = geometry_moments(diagram, density)
    pts, repaired, vor, mom = geo.positions, geo.repaired, geo.voronoi, geo.moments
    n = pts.shape[0]
    family, k = parse_law(config.law, config.hops)
    error = geo.error
    if vor is not None and mom is not None:
        try:
            jac = (centroid_jacobian(vor, mom, density, config.edges)
                   if family in ("tvd-dk", "tvd-c") else None)
            raw = law_command(family, k, config.kappa, pts, mom.centroids, mom.dc_dt, jac)
        except NUMERICAL_ERRORS as exc:
            error = str(exc)
    if error is not None or vor is None or mom is None:
        zero = np.zeros((n, 2))
        state = CoverageState(
            t=float(t), law=config.law, status=f"error: {error}", positions=pts,
            centroids=pts.copy(), masses=np.zeros(n), dc_dt=np.zeros((n, 2)), cost_H=0.0,
            cost_H_normalised=0.0, mean_centroid_distance=0.0,
            max_centroid_distance=0.0, edges=np.zeros((0, 2, 2)),
            neighbours=np.zeros((0, 2), dtype=np.intp), cells=[], packing_warning=packing,
            repaired=repaired, saturated=0, geometry_config=geo.config)
        return zero, state, None
    u = saturate(raw, config.max_speed)
    speed_raw = np.hypot(raw[:, 0], raw[:, 1])
    saturated = int(np.count_nonzero(~np.isfinite(speed_raw) | (
        speed_raw > (config.max_speed if config.max_speed is not None else np.inf))))
    dist = geo.centroid_distances()
    total = float(mom.masses.sum())
    edges = geo.edges
    cells = geo.cell_polygons()  # flat and read-only: no Python object per robot
    for arr in (pts, mom.centroids, mom.masses, mom.dc_dt, edges, vor.edge_pairs):
        if arr.flags.writeable:
            arr.setflags(write=False)
    state = CoverageState(
        t=float(t), law=config.law, status="ok", positions=pts, centroids=mom.centroids,
        masses=mom.masses, dc_dt=mom.dc_dt, cost_H=mom.cost_H, cost_H_normalised=mom.cost_H / total,
        mean_centroid_distance=float(dist.mean()), max_centroid_distance=float(dist.max()),
        edges=edges, neighbours=vor.edge_pairs, cells=cells, packing_warning=packing,
        repaired=repaired, saturated=saturated, geometry_config=geo.config)
    return u, state, jac


class CoverageController:
    """Callable coverage controller: ``nominal, state = ctrl(positions, t)``.

    ``ctrl.density`` (any Density: ``.at(t) -> GaussianMixture``) and ``ctrl.config`` may be
    reassigned between ticks. The packing prediction is refreshed every ``packing_every`` ticks
    and whenever the density object or the number of robots changes.
    """

    def __init__(self, config: CoverageConfig | None = None, density: Density | None = None) -> None:
        self.config = config if config is not None else CoverageConfig()
        if density is None:
            raise ValueError("CoverageController needs a density (an object with .at(t))")
        self.density = density
        self._packing: str | None = None
        self._packing_key: tuple[int, int] | None = None
        self._ticks = 0

    @property
    def density(self) -> Density:
        return self._density

    @density.setter
    def density(self, value: Density) -> None:
        if not callable(getattr(value, "at", None)):
            raise TypeError(f"density must have .at(t) -> GaussianMixture, got {type(value).__name__}")
        self._density = value

    def __call__(self, positions: ArrayLike, t: float) -> tuple[NDArray[np.float64], CoverageState]:
        """Nominal single-integrator velocities (N, 2) [m/s] and the tick's :class:`CoverageState`."""
        return self.step(positions, self._density.at(float(t)), t)

    def step(self, positions: ArrayLike, snapshot: GaussianMixture, t: float
             ) -> tuple[NDArray[np.float64], CoverageState]:
        """:meth:`__call__` with the density's snapshot at ``t`` already taken (``density.at(t)``, e.g. on
        another thread than the one computing): the same velocities (N, 2) m/s and state."""
        return self.finish(self.diagram(positions), snapshot, t)

    def diagram(self, positions: ArrayLike) -> CoverageGeometry:
        """The first half of :meth:`step`: pre-conditioning and the Voronoi diagram of ``positions``
        (N, 2) m (no density needed; touches no state of the controller)."""
        return geometry_diagram(positions, self.config.geometry)

    def finish(self, diagram: CoverageGeometry, snapshot: GaussianMixture, t: float
               ) -> tuple[NDArray[np.float64], CoverageState]:
        """The second half of :meth:`step`: moments, Jacobian and law on :meth:`diagram`'s result."""
        snap = snapshot
        if not isinstance(snap, GaussianMixture):
            raise TypeError(f"density.at(t) must return a GaussianMixture, got {type(snap).__name__}")
        n = int(diagram.positions.shape[0])
        key = (id(self._density), n)
        if key != self._packing_key or self._ticks % self.config.packing_every == 0:
            self._packing = (packing_warning(snap, n, self.config.bounds, self.config.safety_distance)
                             if n >= 2 else None)
            self._packing_key = key
        self._ticks += 1
        u, state, _ = coverage_tick_on(diagram, snap, self.config, t, self._packing)
        return u, state
