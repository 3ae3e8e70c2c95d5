"""The coverage geometry of one tick, computed in one place: live and when a recording is read.

Positions and a density snapshot in, the bounded Voronoi diagram and its cell moments out
(REFERENCE.md §5): pre-condition the positions (clamp ``wall_margin`` inside, push apart robots
closer than ``min_separation``) → bounded Voronoi cells on ``bounds`` → cell moments with the
``quadrature`` options. :func:`coverage_geometry` is what :func:`~swarmdeck.coverage.coverage_tick`
runs every tick, and what the recording codec runs to derive the cells of a recorded frame instead
of storing them; :class:`GeometryConfig` is everything besides the positions and the density that
the result depends on, so a recording stores it (only where it differs from the defaults) and
draws exactly the cells the console drew.

Example::

    geo = coverage_geometry(points, density.at(t), CoverageConfig(law="lloyd").geometry)
    geo.cells(), geo.centroids, geo.masses        # polygons (V_i, 2) m, (N, 2) m, (N,)
"""
from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, fields, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import QhullError

from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds, check_bounds
from swarmdeck.core.config import from_mapping
from swarmdeck.coverage.cells import CellPolygons
from swarmdeck.coverage.density import GaussianMixture
from swarmdeck.coverage.quadrature import CellMoments, QuadratureOptions, cell_moments
from swarmdeck.coverage.voronoi import BoundedVoronoi, bounded_voronoi, precondition_positions

__all__ = ["GeometryConfig", "CoverageGeometry", "coverage_geometry", "geometry_diagram", "geometry_moments",
           "NUMERICAL_ERRORS", "DEFAULT_QUADRATURE"]

#: The quadrature of the coverage controller (REFERENCE.md §5): sub-triangles ≤ 1.25 σ of a nearby bump.
DEFAULT_QUADRATURE = QuadratureOptions(resolution=1.25)
#: What a degenerate diagram or a singular system raises in the coverage numerics (the tick reports it
#: in its status instead of failing).
NUMERICAL_ERRORS: tuple[type[Exception], ...] = (RuntimeError, ValueError, QhullError, np.linalg.LinAlgError)


@dataclass(frozen=True)
class GeometryConfig:
    """What the coverage geometry depends on besides the positions and the density.

    bounds: the arena rectangle (x_min, x_max, y_min, y_max) m; wall_margin m (0 < · < 0.01): robots
    are clamped this far inside; min_separation m (0 ≤ · < 0.1): closer robots are pushed apart;
    quadrature: the cell-moment accuracy options. Raises ValueError naming a bad value.
    """

    bounds: Bounds = DEFAULT_BOUNDS
    wall_margin: float = 1e-6
    min_separation: float = 1e-3
    quadrature: QuadratureOptions = field(default_factory=lambda: DEFAULT_QUADRATURE)

    def __post_init__(self) -> None:
        object.__setattr__(self, "bounds", check_bounds(self.bounds))
        if not (0 < self.wall_margin < 0.01 and 0 <= self.min_separation < 0.1):
            raise ValueError("need 0 < wall_margin < 0.01 m and 0 <= min_separation < 0.1 m")
        if not isinstance(self.quadrature, QuadratureOptions):
            raise ValueError(f"quadrature must be QuadratureOptions, got {type(self.quadrature).__name__}")

    def changes(self, bounds: Bounds) -> dict[str, Any]:
        """JSON-able fields that differ from ``GeometryConfig(bounds=bounds)`` (the defaults on those
        bounds): ``{}`` for a default configuration. :meth:`from_changes` inverts it."""
        base = GeometryConfig(bounds=bounds)
        out: dict[str, Any] = {}
        for f in fields(self):
            mine, theirs = getattr(self, f.name), getattr(base, f.name)
            if mine != theirs:
                out[f.name] = asdict(mine) if isinstance(mine, QuadratureOptions) else (
                    [float(v) for v in mine] if f.name == "bounds" else float(mine))
        return out

    @classmethod
    def from_changes(cls, changes: Mapping[str, Any] | None, bounds: Bounds) -> GeometryConfig:
        """The configuration :meth:`changes` describes on ``bounds``; ValueError naming an unknown key or a
        bad value."""
        quad = lambda sub: (from_mapping(QuadratureOptions, sub, "quadrature", error=ValueError)  # noqa: E731
                            if isinstance(sub, Mapping) else sub)
        data = {"bounds": tuple(bounds), **(changes or {})}
        return from_mapping(cls, data, "coverage geometry config", error=ValueError,
                            convert={"quadrature": quad, "bounds": tuple})


@dataclass(frozen=True)
class CoverageGeometry:
    """The geometry of one tick: positions (N, 2) m as pre-conditioned, repaired: robots moved by
    that; voronoi and moments (None with ``error``, a one-line reason, when the diagram could not be
    built); config: the :class:`GeometryConfig` it was computed with."""

    positions: NDArray[np.float64]
    repaired: int
    voronoi: BoundedVoronoi | None
    moments: CellMoments | None
    config: GeometryConfig
    error: str | None = None

    @property
    def ok(self) -> bool:
        return self.error is None

    def _need(self) -> tuple[BoundedVoronoi, CellMoments]:
        if self.voronoi is None or self.moments is None:
            raise ValueError(f"no coverage geometry: {self.error}")
        return self.voronoi, self.moments

    @property
    def centroids(self) -> NDArray[np.float64]:
        """(N, 2) m, the cell centroids under the density."""
        return self._need()[1].centroids

    @property
    def masses(self) -> NDArray[np.float64]:
        """(N,), ∫φ over each cell."""
        return self._need()[1].masses

    @property
    def edges(self) -> NDArray[np.float64]:
        """(E, 2, 2) m, the shared Voronoi edges as segments."""
        return self._need()[0].edge_segments()

    @property
    def neighbours(self) -> NDArray[np.intp]:
        """(E, 2) robot index pairs sharing an edge."""
        return self._need()[0].edge_pairs

    def cells(self) -> list[NDArray[np.float64]]:
        """N counter-clockwise polygons (V_i, 2) m."""
        return self._need()[0].polygons()

    def cell_polygons(self) -> CellPolygons:
        """The same polygons, flat (concatenated vertices and offsets; what the Frame stores)."""
        return self._need()[0].cell_polygons()

    @property
    def cost_H(self) -> float:
        """Locational cost H = Σ_i ∫_{V_i} ‖q − p_i‖² φ."""
        return float(self._need()[1].cost_H)

    def centroid_distances(self) -> NDArray[np.float64]:
        """(N,) m, ‖p_i − c_i‖ from each pre-conditioned position to its centroid."""
        d = self.centroids - self.positions
        return np.hypot(d[:, 0], d[:, 1])


def coverage_geometry(positions: ArrayLike, density: GaussianMixture, config: GeometryConfig) -> CoverageGeometry:
    """The bounded Voronoi diagram of ``positions`` (N, 2) m on ``config.bounds`` and its cell moments
    under the density snapshot ``density``, after pre-conditioning (module docstring).

    Raises ValueError for malformed positions (wrong shape, not finite); a degenerate diagram or a
    failed integration gives a :class:`CoverageGeometry` with ``error`` set instead.
    """
    return geometry_moments(geometry_diagram(positions, config), density)


def geometry_diagram(positions: ArrayLike, config: GeometryConfig) -> CoverageGeometry:
    """The first half of :func:`coverage_geometry`: pre-conditioning and the diagram, no moments yet
    (``moments`` None; ``error`` set when the diagram could not be built). It needs no density, so a
    pipeline can build tick k's diagram while tick k − 1's moments are integrated. ValueError for
    malformed positions."""
    pts, repaired = precondition_positions(positions, config.bounds, config.wall_margin, config.min_separation)
    try:
        vor = bounded_voronoi(pts, config.bounds)
    except NUMERICAL_ERRORS as exc:
        return CoverageGeometry(pts, repaired, None, None, config, str(exc))
    return CoverageGeometry(pts, repaired, vor, None, config)


def geometry_moments(diagram: CoverageGeometry, density: GaussianMixture) -> CoverageGeometry:
    """The second half of :func:`coverage_geometry`: the cell moments of :func:`geometry_diagram`'s
    diagram under ``density`` (the same bits as the whole); an earlier error is kept."""
    if diagram.voronoi is None:
        return diagram
    try:
        mom = cell_moments(diagram.voronoi, density, diagram.config.quadrature)
    except NUMERICAL_ERRORS as exc:
        return replace(diagram, voronoi=None, moments=None, error=str(exc))
    return replace(diagram, moments=mom)
