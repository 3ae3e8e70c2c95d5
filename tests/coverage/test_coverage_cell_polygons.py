"""A tick's cells kept flat (coverage/cells.py): the same polygons, in the same order and bits, as the list
the diagram gave before; they read as a sequence of N read-only polygons; the Frame takes their arrays."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.console.runtime.frame import CoverageFrame
from swarmdeck.coverage import CoverageConfig, GaussianMixture, bounded_voronoi, coverage_tick, precondition_positions
from swarmdeck.coverage.cells import CellPolygons

BOUNDS = (-1.6, 1.6, -1.0, 1.0)


def _old_polygons(vor) -> list[np.ndarray]:
    """BoundedVoronoi.polygons() as it was before the flat form (the reference)."""
    p = vor.points[vor.tri_cell]
    a = vor.vertices[vor.tri_a] - p
    ang = np.arctan2(a[:, 1], a[:, 0])
    order = np.lexsort((ang, vor.tri_cell))
    verts = vor.vertices[vor.tri_a[order]]
    ends = np.cumsum(np.bincount(vor.tri_cell, minlength=vor.n)).tolist()
    return [verts[a:b] for a, b in zip([0] + ends[:-1], ends)]


@settings(max_examples=25, deadline=None)
@given(st.integers(1, 120), st.integers(0, 2**31 - 1))
def test_the_flat_cells_are_the_old_polygons_bit_for_bit(n: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    pts, _ = precondition_positions(rng.uniform([-1.6, -1.0], [1.6, 1.0], (n, 2)), BOUNDS)
    vor = bounded_voronoi(pts, BOUNDS)
    flat, old = vor.cell_polygons(), _old_polygons(vor)
    assert len(flat) == n and flat.offsets[0] == 0 and flat.offsets[-1] == len(flat.vertices)
    for mine, ref in zip(flat, old):
        assert np.array_equal(mine, ref)
    assert all(np.array_equal(a, b) for a, b in zip(vor.polygons(), old))
    assert np.array_equal(flat[-1], old[-1]) and len(flat[1:3]) == len(old[1:3])


def test_cells_read_as_a_sequence_of_read_only_polygons() -> None:
    cells = CellPolygons.from_list([np.zeros((3, 2)), np.ones((4, 2))])
    assert len(cells) == 2 and cells[1].shape == (4, 2) and [c.shape for c in cells] == [(3, 2), (4, 2)]
    assert not cells.vertices.flags.writeable and not cells[0].flags.writeable
    assert CellPolygons.from_list(cells) is cells and len(CellPolygons.from_list([])) == 0
    with pytest.raises(IndexError, match="cell 2"):
        cells[2]
    with pytest.raises(ValueError, match="offsets"):
        CellPolygons(np.zeros((3, 2)), np.array([0, 2]))


def test_the_frame_takes_the_ticks_cell_arrays() -> None:
    pts = np.random.default_rng(4).uniform([-1.5, -0.9], [1.5, 0.9], (40, 2))
    density = GaussianMixture(0.05, [[0.2, 0.1]], [0.4], [1.0])
    _, state, _ = coverage_tick(pts, density, CoverageConfig(bounds=BOUNDS), 0.0)
    assert isinstance(state.cells, CellPolygons) and len(state.cells) == 40
    frame = CoverageFrame.from_state(state)
    assert np.array_equal(frame.cell_vertices, state.cells.vertices)
    assert np.array_equal(frame.cell_offsets, state.cells.offsets)
    assert [c.tolist() for c in frame.cells()] == state.to_dict()["cells"]
