"""What an rps script plots on its figure, as annotations on the arena (the Robotarium 2.0's projector rule).

The Robotarium's guide: "anything that you plot within the boundaries … will be projected onto the
testbed". :func:`figure_annotations` reads the script's artists on ``r.axes`` — patches (circles,
rectangles, polygons, any path), lines (``plot``: polylines, or dots when drawn with markers and no line),
collections (``scatter``, line and polygon collections) and texts — and turns those inside the arena
into :class:`~swarmdeck.core.annotations.Annotations`: every coordinate through the artist's own transform
and back through the axes' data transform (so positions in axes or figure coordinates land where the
figure shows them), sizes in points (line widths, marker sizes, font sizes) converted to metres at the
figure's scale, colours as RGBA with the artist's alpha. An artist wholly outside the arena, invisible,
or of another kind (images, legends) is skipped; a primitive reaching outside is clipped to the arena
later (:func:`~swarmdeck.core.annotations.sanitize`). Arena artists swarmdeck itself adds are marked with
:data:`SWARMDECK_GID` and skipped.
"""
from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmdeck.core.annotations import CIRCLE, EMPTY, POINT, POLYGON, POLYLINE, TEXT, Annotations
from swarmdeck.core.bounds import Bounds

#: the gid of the artists swarmdeck draws on the rps figure itself (not the script's)
SWARMDECK_GID = "swarmdeck-arena"


class _Builder:
    """The primitives of one figure, in the artists' order, joined into one :class:`Annotations` at the end: each
    :meth:`one`/:meth:`add` only remembers its pieces (no array work per artist), :meth:`build` joins them with a
    few numpy calls."""

    def __init__(self) -> None:
        self.kinds: list[int] = []  # per piece: its kind, its primitive count, filled
        self.ps: list[int] = []
        self.filled: list[bool] = []
        self.counts: list[Any] = []  # per piece: one vertex count (int), or (p,) of them
        self.vertices: list[NDArray[np.float64]] = []
        self.sizes: list[Any] = []  # per piece: one size, or (p,)
        self.colors: list[NDArray[np.uint8]] = []  # per piece: (p, 4)
        self.texts: list[str] = []

    def one(self, kind: int, vertices: NDArray[np.float64], size: Any, colour: Any, filled: bool,
            text: str = "") -> None:
        """One primitive of ``kind`` over ``vertices`` (V, 2) m, ``size`` m, ``colour`` (4,) or (1, 4) uint8 (no rows:
        an invisible colour, nothing is added): what :meth:`add` does with one primitive."""
        colour = np.asarray(colour, dtype=np.uint8)
        if not colour.size:
            return
        vertices = np.asarray(vertices, dtype=float).reshape(-1, 2)
        self.kinds.append(kind)
        self.ps.append(1)
        self.filled.append(bool(filled))
        self.counts.append(len(vertices))
        self.vertices.append(vertices)
        self.sizes.append(size if np.ndim(size) == 0 else np.broadcast_to(np.asarray(size, dtype=float), (1,)))
        self.colors.append(colour if colour.shape == (1, 4) else np.broadcast_to(colour, (1, 4)))
        self.texts.append(text)

    def add(self, kind: int, vertices: NDArray[np.float64], counts: Any, sizes: Any, colors: Any,
            filled: bool, texts: list[str] | None = None) -> None:
        """``counts`` (p,) primitives of ``kind`` over ``vertices`` (V, 2) m; ``sizes`` one or (p,) m; ``colors``
        (4,), (1, 4) or (p, 4) uint8 (no rows: an invisible colour, nothing is added)."""
        p = len(counts)
        colors = np.asarray(colors, dtype=np.uint8)
        if not p or not colors.size:  # nothing, or an invisible colour ("none")
            return
        if colors.shape != (p, 4):
            colors = np.broadcast_to(colors, (p, 4))
        self.kinds.append(kind)
        self.ps.append(p)
        self.filled.append(bool(filled))
        self.counts.append(np.asarray(counts, dtype=np.int64).reshape(-1))
        self.vertices.append(np.asarray(vertices, dtype=float).reshape(-1, 2))
        self.sizes.append(np.broadcast_to(np.asarray(sizes, dtype=float), (p,)))
        self.colors.append(colors)
        self.texts.extend(texts if texts is not None else [""] * p)

    @staticmethod
    def _join(pieces: list[Any], dtype: Any) -> NDArray[Any]:
        """Pieces of one value each (ints, floats) or arrays of several, in order, as one 1-D array of ``dtype``."""
        parts: list[NDArray[Any]] = []
        run: list[Any] = []
        for piece in pieces:
            if isinstance(piece, np.ndarray) and piece.ndim:
                if run:
                    parts.append(np.array(run, dtype=dtype))
                    run = []
                parts.append(piece)
            else:
                run.append(piece)
        if run:
            parts.append(np.array(run, dtype=dtype))
        return parts[0].astype(dtype, copy=False) if len(parts) == 1 else np.concatenate(parts).astype(dtype,
                                                                                                       copy=False)

    def build(self) -> Annotations:
        if not self.kinds:
            return EMPTY
        ps = np.array(self.ps, dtype=np.intp)
        counts = self._join(self.counts, np.int64)
        return Annotations(kinds=np.repeat(np.array(self.kinds, dtype=np.uint8), ps),
                           offsets=np.concatenate(([0], np.cumsum(counts))),
                           vertices=np.concatenate(self.vertices), sizes=self._join(self.sizes, float),
                           colors=np.concatenate(self.colors), filled=np.repeat(np.array(self.filled), ps),
                           texts=tuple(self.texts))


def _rgba(colors: Any, alpha: float | None) -> NDArray[np.uint8]:
    """matplotlib colour(s) → (K, 4) uint8; the artist's alpha multiplies in when set."""
    from matplotlib.colors import to_rgba_array

    c = to_rgba_array(colors)
    if alpha is not None:
        c[:, 3] = float(alpha)
    return np.clip(np.round(c * 255.0), 0, 255).astype(np.uint8)


#: the types of a colour tuple's entries :class:`Colours` resolves through matplotlib's ``to_rgba`` (plain numbers:
#: equal values convert alike); any other colour takes :func:`_rgba`'s path
_PLAIN_NUMBERS = (float, int, np.float64, np.float32, np.int64, np.int32)
_NO_ROWS = np.zeros((0, 4), dtype=np.uint8)
_NO_ROWS.setflags(write=False)


class Colours:
    """:func:`_rgba` for the colours one figure draws step after step, without its array work each time.

    A single colour — a string or a tuple of 3 or 4 plain numbers — is resolved by matplotlib's ``to_rgba``
    (``to_rgba_array``'s own path for one colour: its cache, its colour cycle ``"C0"`` resolved every call, named
    colours as matplotlib has them now); its RGBA floats and the alpha (``float``) are then the key of the uint8
    row, a pure function of those numbers (the same formula as :func:`_rgba`): nothing is keyed on an object. Every
    other colour (arrays, lists, a colour matplotlib refuses) takes :func:`_rgba` itself. At most ``limit`` rows are
    kept (then the memo starts over)."""

    def __init__(self, limit: int = 4096) -> None:
        self.limit = int(limit)
        self._rows: dict[tuple[tuple[float, ...], float | None], NDArray[np.uint8]] = {}

    def rgba(self, colors: Any, alpha: Any) -> NDArray[np.uint8]:
        """(K, 4) uint8 as :func:`_rgba` ``(colors, alpha)`` gives (read-only; K = 0 for ``"none"``)."""
        if isinstance(colors, str):
            if colors.lower() == "none":  # to_rgba_array: no rows, whatever the alpha (_rgba still reads it)
                if alpha is not None:
                    float(alpha)
                return _NO_ROWS
        elif not (type(colors) is tuple and len(colors) in (3, 4) and all(type(x) in _PLAIN_NUMBERS for x in colors)):
            return _rgba(colors, alpha)
        from matplotlib.colors import to_rgba

        try:
            floats = to_rgba(colors)
        except (TypeError, ValueError):  # _rgba's path raises its own error (or finds another reading)
            return _rgba(colors, alpha)
        key = (floats, None if alpha is None else float(alpha))
        row = self._rows.get(key)
        if row is None:
            c = np.array([floats], dtype=float)
            if key[1] is not None:
                c[:, 3] = key[1]
            row = np.clip(np.round(c * 255.0), 0, 255).astype(np.uint8)
            row.setflags(write=False)
            if len(self._rows) >= self.limit:
                self._rows.clear()
            self._rows[key] = row
        return row


def _inside(xy: NDArray[np.float64], b: Bounds) -> NDArray[np.bool_]:
    return np.asarray((xy[..., 0] >= b.x_min) & (xy[..., 0] <= b.x_max) & (xy[..., 1] >= b.y_min)
                      & (xy[..., 1] <= b.y_max))


def _inside_one(xy: NDArray[np.float64], b: Bounds) -> bool:
    """:func:`_inside` of the one point ``xy`` (1, 2) (the same comparisons, on its two floats)."""
    x, y = xy[0]
    return bool(b.x_min <= x <= b.x_max and b.y_min <= y <= b.y_max)


def figure_annotations(axes: Any, bounds: Bounds | tuple[float, float, float, float], *,
                       colours: Colours | None = None) -> Annotations:
    """The annotations of what the script drew on ``axes`` inside the arena ``bounds`` (module docstring).

    ``colours``: the :class:`Colours` of this figure kept from step to step (the rps facade's); None: a fresh one."""
    from matplotlib.collections import Collection, LineCollection, PathCollection
    from matplotlib.lines import Line2D
    from matplotlib.patches import Circle, Patch
    from matplotlib.text import Text

    b = Bounds.of(bounds)
    rgba = (colours if colours is not None else Colours()).rgba
    trans_data = axes.transData
    inverse: list[Any] = []  # the data transform's inverse, made when an artist needs it
    origin, unit = axes.transData.transform([[0.0, 0.0], [1.0, 0.0]])
    px_per_m = max(abs(float(unit[0] - origin[0])), 1e-9)
    m_per_pt = axes.figure.dpi / 72.0 / px_per_m
    out = _Builder()
    spines = list(axes.spines.values())

    def data(xy: Any, transform: Any) -> NDArray[np.float64]:
        pts = np.asarray(xy, dtype=float).reshape(-1, 2)
        if transform is trans_data or not len(pts):  # data coordinates already: exact
            return pts
        if not inverse:
            inverse.append(trans_data.inverted())
        return np.asarray(inverse[0].transform(transform.transform(pts)), dtype=float)

    for artist in axes.get_children():
        if not artist.get_visible() or artist.get_gid() == SWARMDECK_GID or artist in spines:
            continue
        if isinstance(artist, Patch) and artist is not axes.patch:
            filled = bool(artist.get_fill())
            colour = rgba(artist.get_facecolor() if filled else artist.get_edgecolor(), artist.get_alpha())
            width = artist.get_linewidth() * m_per_pt
            if isinstance(artist, Circle):
                c = data([artist.center], artist.get_data_transform())
                edge = data([[artist.center[0] + artist.radius, artist.center[1]]], artist.get_data_transform())
                if _inside_one(c, b):
                    out.one(CIRCLE, c, float(np.linalg.norm(edge - c)), colour, filled)
                continue
            for poly in artist.get_path().to_polygons(artist.get_patch_transform()):
                xy = data(poly, artist.get_data_transform())
                if len(xy) > 1 and np.allclose(xy[0], xy[-1]):
                    xy = xy[:-1]
                if len(xy) >= 3 and _inside(xy, b).any():
                    out.one(POLYGON, xy, width, colour, filled)
        elif isinstance(artist, Line2D):
            xy = data(artist.get_xydata(), artist.get_transform())
            finite = np.isfinite(xy).all(axis=1)
            if not finite.all():
                xy = xy[finite]
            if len(xy) == 1:
                if not _inside_one(xy, b):
                    continue
                inside_mask = None  # the one point
            else:
                inside_mask = _inside(xy, b)
                if not len(xy) or not inside_mask.any():
                    continue
            colour = rgba(artist.get_color(), artist.get_alpha())
            if artist.get_linestyle() not in ("None", "", " ", "none") and len(xy) >= 2:
                out.one(POLYLINE, xy, artist.get_linewidth() * m_per_pt, colour, False)
            if artist.get_marker() not in (None, "None", "", " ", "none"):
                inside = xy if inside_mask is None else xy[inside_mask]
                face = rgba(artist.get_markerfacecolor(), artist.get_alpha())
                hollow = not len(face)  # markerfacecolor "none": an outlined marker in its edge colour
                dot_colour = rgba(artist.get_markeredgecolor(), artist.get_alpha()) if hollow else face
                if len(inside) == 1:
                    out.one(POINT, inside, artist.get_markersize() / 2 * m_per_pt, dot_colour, not hollow)
                else:
                    out.add(POINT, inside, np.ones(len(inside), dtype=np.int64),
                            artist.get_markersize() / 2 * m_per_pt, dot_colour, not hollow)
        elif isinstance(artist, Collection):
            alpha = artist.get_alpha()
            if isinstance(artist, PathCollection):  # scatter
                offsets = data(artist.get_offsets(), artist.get_offset_transform())
                keep = _inside(offsets, b) & np.isfinite(offsets).all(axis=1)
                if not keep.any():
                    continue
                k = len(offsets)
                sizes = np.resize(np.asarray(artist.get_sizes(), dtype=float), k) if len(artist.get_sizes()) else np.full(k, 36.0)
                faces = artist.get_facecolor()
                dots = rgba(faces if len(faces) else artist.get_edgecolor(), alpha)
                dots = np.resize(dots, (k, 4)) if len(dots) else np.zeros((k, 4), dtype=np.uint8)
                out.add(POINT, offsets[keep], np.ones(int(keep.sum()), dtype=np.int64),
                        np.sqrt(sizes[keep]) / 2 * m_per_pt, dots[keep], True)
            elif isinstance(artist, LineCollection):
                segs = artist.get_segments()
                cols = rgba(artist.get_colors(), alpha) if len(artist.get_colors()) else np.zeros((1, 4), dtype=np.uint8)
                widths = np.atleast_1d(np.asarray(artist.get_linewidth(), dtype=np.float64))
                for i, seg in enumerate(segs):
                    xy = data(seg, artist.get_transform())
                    if len(xy) >= 2 and _inside(xy, b).any():
                        out.one(POLYLINE, xy, widths[i % len(widths)] * m_per_pt if len(widths) else 0.01,
                                cols[i % len(cols)], False)
            else:  # polygon / patch collections
                faces = artist.get_facecolor()
                filled = bool(len(faces))
                cols = rgba(faces if filled else artist.get_edgecolor(), alpha) if len(faces) or len(artist.get_edgecolor()) else np.zeros((1, 4), dtype=np.uint8)
                for i, path in enumerate(artist.get_paths()):
                    for poly in path.to_polygons():
                        xy = data(poly, artist.get_transform())
                        if len(xy) > 1 and np.allclose(xy[0], xy[-1]):
                            xy = xy[:-1]
                        if len(xy) >= 3 and _inside(xy, b).any():
                            out.one(POLYGON, xy, 0.01, cols[i % len(cols)], filled)
        elif isinstance(artist, Text):
            text = artist.get_text()
            if not text:
                continue
            xy = data([artist.get_position()], artist.get_transform())
            if _inside_one(xy, b):
                out.one(TEXT, xy, artist.get_fontsize() * m_per_pt, rgba(artist.get_color(), artist.get_alpha()),
                        False, text)
    return out.build()
