"""swarmdeck.coverage: time-varying-density coverage control (REFERENCE.md §5).

    ctrl = CoverageController(CoverageConfig(law="tvd-d1"), density)   # any Density: .at(t)
    nominal, state = ctrl(positions, t)      # (N, 2) m/s → safety filter; CoverageState

Densities: :class:`GaussianMixture` (snapshot with analytic φ_t, isotropic or anisotropic bumps;
``merge_mixtures`` adds the bumps of several),
:class:`AnalyticDensity` of :class:`Bump` s that move/grow/fade/rotate (``s1_density``,
``moving_density``), ``image_density`` (grey image → static mixture). Numerics, usable on their
own: ``coverage_geometry`` (pre-conditioning, cells and moments of one tick, as the controller and
the recordings compute them), ``precondition_positions``, ``bounded_voronoi``, ``cell_moments``, ``centroid_jacobian``,
``raster_moments`` (test oracle), ``predicted_spacing``/``packing_warning``; laws in
:mod:`swarmdeck.coverage.laws`; scenario S1 in :mod:`swarmdeck.coverage.scenario`.
Group behaviours (consensus, formation): :mod:`swarmdeck.coverage.group`; their interaction graphs
are in :mod:`swarmdeck.core.graphs` (shared with the rps facade).
"""
from swarmdeck.core.kinematics import saturate
from swarmdeck.coverage.controller import CoverageConfig, CoverageController, CoverageState, coverage_tick
from swarmdeck.coverage.densities import (
                                           AnalyticDensity,
                                           Bump,
                                           Constant,
                                           Fixed,
                                           Linear,
                                           Lissajous,
                                           Orbit,
                                           Pulse,
                                           Sine,
                                           moving_density,
                                           s1_density,
)
from swarmdeck.coverage.density import Density, GaussianMixture, merge_mixtures
from swarmdeck.coverage.geometry import CoverageGeometry, GeometryConfig, coverage_geometry
from swarmdeck.coverage.image import image_density, letter_image
from swarmdeck.coverage.jacobian import EdgeOptions, centroid_jacobian
from swarmdeck.coverage.laws import LAWS, parse_law
from swarmdeck.coverage.packing import packing_warning, predicted_spacing
from swarmdeck.coverage.quadrature import CellMoments, QuadratureOptions, cell_moments
from swarmdeck.coverage.raster import raster_moments
from swarmdeck.coverage.voronoi import BoundedVoronoi, bounded_voronoi, precondition_positions

__all__ = [
    "AnalyticDensity", "BoundedVoronoi", "Bump", "CellMoments", "Constant", "CoverageConfig",
    "CoverageController", "CoverageGeometry", "CoverageState", "Density", "GeometryConfig", "EdgeOptions", "Fixed", "GaussianMixture",
    "LAWS", "Linear", "Lissajous", "Orbit", "Pulse", "QuadratureOptions", "Sine",
    "bounded_voronoi", "cell_moments", "centroid_jacobian", "coverage_geometry", "coverage_tick", "image_density",
    "letter_image", "merge_mixtures", "moving_density", "packing_warning", "parse_law",
    "precondition_positions", "predicted_spacing", "raster_moments", "s1_density", "saturate",
]
