"""The compiled Voronoi post-processing (coverage/voronoi_kernels.py) gives the numpy diagram bit for bit.

Random robots (uniform, bunched far from the walls — the path that adds reflections —, on a grid: cocircular
points), on the unit floor and the console's 22 × 13 m floor: the diagram built with the kernels equals the one
built with ``kernels.AVAILABLE`` off in every array, every bit and every dtype, and so do its areas and its cell
polygons (the compiled counting + insertion sort against ``np.lexsort``).
"""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.coverage import bounded_voronoi, kernels, precondition_positions, voronoi_kernels

FLOORS = [(-1.6, 1.6, -1.0, 1.0), (-11.0, 11.0, -6.5, 6.5)]
FIELDS = ("points", "vertices", "tri_cell", "tri_a", "tri_b", "edge_pairs", "edge_vertices")


def _both(p: np.ndarray, bounds: tuple[float, float, float, float]):
    compiled = bounded_voronoi(p, bounds)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(kernels, "AVAILABLE", False)
        reference = bounded_voronoi(p, bounds)
        ref_areas = reference.areas()
        ref_cells = reference.cell_polygons()
    return compiled, reference, ref_areas, ref_cells


def _same(a: np.ndarray, b: np.ndarray) -> None:
    assert a.dtype == b.dtype and a.shape == b.shape
    assert a.tobytes() == b.tobytes()


def _check(p: np.ndarray, bounds: tuple[float, float, float, float]) -> None:
    compiled, reference, ref_areas, cells_r = _both(p, bounds)
    for name in FIELDS:
        _same(getattr(compiled, name), getattr(reference, name))
    _same(compiled.areas(), ref_areas)
    cells_c = compiled.cell_polygons()
    _same(cells_c.vertices, cells_r.vertices)
    _same(cells_c.offsets, cells_r.offsets)


def test_the_voronoi_kernels_are_compiled() -> None:
    assert kernels.AVAILABLE
    assert hasattr(voronoi_kernels._ridges, "py_func") and hasattr(voronoi_kernels._assemble, "py_func")


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 400), floor=st.sampled_from([0, 1]),
       layout=st.sampled_from(["uniform", "bunched", "grid"]))
def test_compiled_diagram_equals_the_numpy_diagram_bit_for_bit(seed: int, n: int, floor: int, layout: str) -> None:
    bounds = FLOORS[floor]
    rng = np.random.default_rng(seed)
    lo, hi = np.array(bounds)[[0, 2]], np.array(bounds)[[1, 3]]
    if layout == "uniform":
        raw = rng.uniform(lo, hi, (n, 2))
    elif layout == "bunched":
        raw = rng.uniform(lo, hi) + rng.normal(0.0, 0.02 * (hi - lo).min(), (n, 2))
    else:
        k = int(np.ceil(np.sqrt(n)))
        g = np.stack(np.meshgrid(np.linspace(0.1, 0.9, k), np.linspace(0.1, 0.9, k)), axis=-1).reshape(-1, 2)[:n]
        raw = lo + g * (hi - lo)
    p, _ = precondition_positions(raw, bounds)
    _check(p, bounds)


def test_five_thousand_robots_on_the_console_floor() -> None:
    bounds = FLOORS[1]
    p, _ = precondition_positions(np.random.default_rng(7).uniform([-11.0, -6.5], [11.0, 6.5], (5000, 2)), bounds)
    _check(p, bounds)


def test_quadrature_points_equal_the_numpy_points_bit_for_bit() -> None:
    rng = np.random.default_rng(3)
    tri = rng.normal(0.0, 0.3, (500, 3, 2))
    cell = np.sort(rng.integers(0, 40, 500))
    origin = rng.uniform(-11.0, 11.0, (40, 2))
    bary = rng.dirichlet(np.ones(3), 7)
    for got, want in zip(kernels.quadrature_points(tri, cell, bary, origin),
                         kernels.quadrature_points_numpy(tri, cell, bary, origin)):
        _same(got, want)
