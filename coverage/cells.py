"""The N cell polygons of one tick, kept flat: concatenated vertices and offsets (REFERENCE.md §5).

A list of N small arrays costs a Python object per robot at every step that touches it (building,
freezing, flattening again for the Frame and the recording): at N = 5000 that was ≈ 30 ms of a
console tick. :class:`CellPolygons` keeps the one flat form the Frame, the recording and the
renderers use (``vertices`` (V, 2) m, ``offsets`` (N + 1,)) and still reads as the sequence of N
polygons it replaces (``len``, indexing, iteration give read-only (V_i, 2) views).

Example::

    cells = vor.cell_polygons()          # from a BoundedVoronoi
    cells.vertices, cells.offsets        # (V, 2) m, (N + 1,) int64
    cells[3]                             # robot 3's counter-clockwise polygon (V_3, 2) m
"""
from __future__ import annotations

from collections.abc import Iterator, Sequence
from typing import overload

import numpy as np
from numpy.typing import NDArray

__all__ = ["CellPolygons"]


class CellPolygons(Sequence[NDArray[np.float64]]):
    """N polygons as concatenated vertices ``vertices`` (V, 2) m and ``offsets`` (N + 1,) int64
    (polygon i is ``vertices[offsets[i]:offsets[i + 1]]``). Both arrays are made read-only (copies
    only when the input is not already float64 / int64). Raises ValueError for malformed offsets."""

    __slots__ = ("vertices", "offsets")

    def __init__(self, vertices: NDArray[np.float64], offsets: NDArray[np.int64]) -> None:
        verts = np.asarray(vertices, dtype=float).reshape(-1, 2)
        offs = np.asarray(offsets, dtype=np.int64).reshape(-1)
        if offs.size < 1 or offs[0] != 0 or offs[-1] != verts.shape[0] or np.any(np.diff(offs) < 0):
            raise ValueError(f"cell offsets must rise from 0 to the number of vertices {verts.shape[0]}")
        for arr in (verts, offs):
            if arr.flags.writeable:
                arr.setflags(write=False)
        self.vertices: NDArray[np.float64] = verts
        self.offsets: NDArray[np.int64] = offs

    @classmethod
    def empty(cls) -> CellPolygons:
        """No cells (N = 0)."""
        return cls(np.empty((0, 2)), np.zeros(1, dtype=np.int64))

    @classmethod
    def from_list(cls, polygons: Sequence[NDArray[np.float64]]) -> CellPolygons:
        """From polygons (V_i, 2) m (already a :class:`CellPolygons`: returned as it is)."""
        if isinstance(polygons, CellPolygons):
            return polygons
        if len(polygons) == 0:
            return cls.empty()
        arrs = [np.asarray(c, dtype=float).reshape(-1, 2) for c in polygons]
        sizes = np.fromiter((len(a) for a in arrs), dtype=np.int64, count=len(arrs))
        return cls(np.concatenate(arrs, axis=0), np.concatenate(([0], np.cumsum(sizes))).astype(np.int64))

    def __len__(self) -> int:
        return int(self.offsets.shape[0]) - 1

    @overload
    def __getitem__(self, i: int) -> NDArray[np.float64]: ...

    @overload
    def __getitem__(self, i: slice) -> list[NDArray[np.float64]]: ...

    def __getitem__(self, i: int | slice) -> NDArray[np.float64] | list[NDArray[np.float64]]:
        if isinstance(i, slice):
            return [self[k] for k in range(*i.indices(len(self)))]
        n = len(self)
        k = int(i) + n if int(i) < 0 else int(i)
        if not 0 <= k < n:
            raise IndexError(f"cell {i} out of range for {n} cells")
        return self.vertices[self.offsets[k]:self.offsets[k + 1]]

    def __iter__(self) -> Iterator[NDArray[np.float64]]:
        o = self.offsets.tolist()
        verts = self.vertices
        return (verts[a:b] for a, b in zip(o[:-1], o[1:]))

    def __repr__(self) -> str:
        return f"CellPolygons({len(self)} cells, {self.vertices.shape[0]} vertices)"
