"""What an experiment draws on the arena: points, polylines, circles, polygons and text, in arena metres.

One batch of primitives is an :class:`Annotations` — flat read-only arrays, P primitives, V vertices:

* ``kinds`` (P,) uint8: :data:`POINT`, :data:`POLYLINE` (a line is a 2-vertex polyline), :data:`CIRCLE`,
  :data:`POLYGON`, :data:`TEXT`;
* ``offsets`` (P + 1,) int64: primitive i is ``vertices[offsets[i]:offsets[i + 1]]``; a point, circle and text
  have one vertex (the centre / the anchor: text is centred on it), a polyline ≥ 2, a polygon ≥ 3;
* ``vertices`` (V, 2) float64, m, arena coordinates;
* ``sizes`` (P,) float64, m: a point's and a circle's radius, a text's height, a polyline's and a polygon
  outline's width;
* ``colors`` (P, 4) uint8 RGBA; ``filled`` (P,) bool (a circle or polygon drawn filled);
* ``texts`` (P,) str: the text of a TEXT primitive, ``""`` for the others.

Everything outside the process that built it (a sandboxed script's message, a recording) is untrusted:
:func:`sanitize` is the one place the caps of :class:`AnnotationLimits` are applied — non-finite
coordinates or sizes refuse the primitive, coordinates outside the arena are clipped to it, sizes above
the arena's diagonal are clipped, texts are cut at ``max_text`` characters (control characters become
spaces), and a tick's primitives, vertices and text beyond the caps are dropped — every change counted in an
:class:`AnnotationReport` whose :meth:`~AnnotationReport.messages` say what was done and which cap applied.
Its cost is linear in what it keeps plus O(P) numpy for what it drops, so a million primitives cost
milliseconds, never a stall. :class:`~swarmdeck.core.annotator.Annotator` builds batches for an experiment
(the drawing API with colours and lifetimes).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.bounds import Bounds

POINT, POLYLINE, CIRCLE, POLYGON, TEXT = 0, 1, 2, 3, 4
KIND_NAMES = ("point", "polyline", "circle", "polygon", "text")
#: vertices a primitive of each kind needs: (at least, at most); -1: no upper limit
_VERTEX_COUNTS = ((1, 1), (2, -1), (1, 1), (3, -1), (1, 1))


@dataclass(frozen=True)
class AnnotationLimits:
    """The caps on what an experiment draws in one tick (:func:`sanitize`).

    Attributes:
        max_primitives: primitives drawn per tick; the rest are dropped (counted).
        max_vertices: vertices drawn per tick, all primitives together; primitives past it are dropped.
        max_text: characters of one text; longer texts are cut (counted).
        max_total_text: characters of all texts of a tick; texts past it are dropped.
        max_size: the largest radius / height / width, m; None: the arena's diagonal.
    """

    max_primitives: int = 4096
    max_vertices: int = 65536
    max_text: int = 200
    max_total_text: int = 32768
    max_size: float | None = None

    def __post_init__(self) -> None:
        for name in ("max_primitives", "max_vertices", "max_text", "max_total_text"):
            value = getattr(self, name)
            if not isinstance(value, (int, np.integer)) or value < 0:
                raise ValueError(f"AnnotationLimits.{name} must be a non-negative integer, got {value!r}")
        if self.max_size is not None and not (math.isfinite(self.max_size) and self.max_size > 0):
            raise ValueError(f"AnnotationLimits.max_size must be a positive number of metres, got {self.max_size!r}")

    def size_cap(self, bounds: Bounds) -> float:
        """The largest size, m: ``max_size`` or the diagonal of ``bounds``."""
        if self.max_size is not None:
            return float(self.max_size)
        b = Bounds.of(bounds)
        return float(math.hypot(b.width, b.height))


DEFAULT_LIMITS = AnnotationLimits()


def _ro(a: ArrayLike, dtype: Any, shape_tail: tuple[int, ...], name: str) -> NDArray[Any]:
    arr: NDArray[Any] = np.array(a, dtype=dtype, copy=True)
    if arr.size == 0:
        arr = arr.reshape((0,) + shape_tail)
    if arr.ndim != 1 + len(shape_tail) or arr.shape[1:] != shape_tail:
        want = "(n" + "".join(f", {s}" for s in shape_tail) + ")"
        raise ValueError(f"annotations: {name} must have shape {want}, got {arr.shape}")
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class Annotations:
    """A batch of P primitives (module docstring). Built from any array-likes; read-only after.

    The constructor checks the structure (shapes, kinds, vertex counts per kind, offsets) and raises
    ValueError naming what is wrong; it does not check the values (finite, inside the arena, sizes,
    text lengths): :func:`sanitize` does, against the caps.
    """

    kinds: NDArray[np.uint8] = field(default_factory=lambda: np.zeros(0, dtype=np.uint8))
    offsets: NDArray[np.int64] = field(default_factory=lambda: np.zeros(1, dtype=np.int64))
    vertices: NDArray[np.float64] = field(default_factory=lambda: np.zeros((0, 2)))
    sizes: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    colors: NDArray[np.uint8] = field(default_factory=lambda: np.zeros((0, 4), dtype=np.uint8))
    filled: NDArray[np.bool_] = field(default_factory=lambda: np.zeros(0, dtype=bool))
    texts: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        kinds = np.asarray(self.kinds)
        if kinds.size and (kinds.dtype.kind not in "iu" or kinds.min() < 0 or kinds.max() > TEXT):
            raise ValueError(f"annotations: kinds must be integers 0..{TEXT} ({', '.join(KIND_NAMES)})")
        set_ = object.__setattr__
        set_(self, "kinds", _ro(kinds, np.uint8, (), "kinds"))
        p = len(self.kinds)
        set_(self, "offsets", _ro(self.offsets, np.int64, (), "offsets"))
        set_(self, "vertices", _ro(self.vertices, np.float64, (2,), "vertices"))
        set_(self, "sizes", _ro(self.sizes, np.float64, (), "sizes"))
        set_(self, "colors", _ro(self.colors, np.uint8, (4,), "colors"))
        set_(self, "filled", _ro(self.filled, bool, (), "filled"))
        if not isinstance(self.texts, (tuple, list)) or not all(isinstance(t, str) for t in self.texts):
            raise ValueError("annotations: texts must be a sequence of str")
        set_(self, "texts", tuple(self.texts))
        o = self.offsets
        if len(o) != p + 1 or o[0] != 0 or o[-1] != len(self.vertices):
            raise ValueError(f"annotations: offsets must have {p + 1} entries from 0 to {len(self.vertices)} "
                             f"(the vertex count), got {len(o)} entries")
        for name in ("sizes", "colors", "filled", "texts"):
            if len(getattr(self, name)) != p:
                raise ValueError(f"annotations: {name} has {len(getattr(self, name))} rows for {p} primitives")
        if p and (np.diff(o) < 0).any():
            raise ValueError("annotations: offsets must not decrease")
        if p:
            counts = np.diff(o)
            lo = np.array([c[0] for c in _VERTEX_COUNTS])[self.kinds]
            hi = np.array([c[1] for c in _VERTEX_COUNTS])[self.kinds]
            bad = (counts < lo) | ((hi >= 0) & (counts > hi))
            if bad.any():
                i = int(np.flatnonzero(bad)[0])
                raise ValueError(f"annotations: primitive {i} ({KIND_NAMES[self.kinds[i]]}) has {int(counts[i])} "
                                 f"vertices (a point, circle or text has 1, a polyline ≥ 2, a polygon ≥ 3)")

    @classmethod
    def _unchecked(cls, kinds: NDArray[np.uint8], offsets: NDArray[np.int64], vertices: NDArray[np.float64],
                   sizes: NDArray[np.float64], colors: NDArray[np.uint8], filled: NDArray[np.bool_],
                   texts: tuple[str, ...]) -> Annotations:
        """A batch from arrays of the right dtypes and shapes that the caller built itself (the drawing API's
        own primitives): no structural check, arrays made read-only in place. Never for outside data."""
        out = object.__new__(cls)
        for name, value in (("kinds", kinds), ("offsets", offsets), ("vertices", vertices), ("sizes", sizes),
                            ("colors", colors), ("filled", filled)):
            value.setflags(write=False)
            object.__setattr__(out, name, value)
        object.__setattr__(out, "texts", texts)
        return out

    def __len__(self) -> int:
        return len(self.kinds)

    def vertex_counts(self) -> NDArray[np.int64]:
        """(P,) vertices of each primitive."""
        return np.diff(self.offsets)

    def anchors(self) -> NDArray[np.float64]:
        """(P,) first vertex of each primitive (the centre of a point or circle, a text's anchor), m."""
        return self.vertices[self.offsets[:-1]] if len(self) else np.zeros((0, 2))

    def select(self, keep: NDArray[np.bool_]) -> Annotations:
        """The primitives where ``keep`` (P,) is True, in order."""
        keep = np.asarray(keep, dtype=bool)
        if keep.all():
            return self
        counts = self.vertex_counts()
        vmask = np.repeat(keep, counts)
        return Annotations(kinds=self.kinds[keep], offsets=np.concatenate(([0], np.cumsum(counts[keep]))),
                           vertices=self.vertices[vmask], sizes=self.sizes[keep], colors=self.colors[keep],
                           filled=self.filled[keep], texts=tuple(t for t, k in zip(self.texts, keep) if k))

    @staticmethod
    def concat(parts: list[Annotations]) -> Annotations:
        """One batch of ``parts`` in order."""
        parts = [a for a in parts if len(a)]
        if not parts:
            return EMPTY
        if len(parts) == 1:
            return parts[0]
        counts = np.concatenate([a.vertex_counts() for a in parts])
        return Annotations(kinds=np.concatenate([a.kinds for a in parts]),
                           offsets=np.concatenate(([0], np.cumsum(counts))),
                           vertices=np.concatenate([a.vertices for a in parts]),
                           sizes=np.concatenate([a.sizes for a in parts]),
                           colors=np.concatenate([a.colors for a in parts]),
                           filled=np.concatenate([a.filled for a in parts]),
                           texts=tuple(t for a in parts for t in a.texts))

    # ---------------------------------------------------------------- plain data (Frame.to_dict, messages)
    def to_dict(self) -> dict[str, Any]:
        """JSON-able: ``{kinds, offsets, vertices, sizes, colors, filled, texts}`` as lists (floats exact;
        non-finite floats as the strings "NaN"/"Infinity"/"-Infinity", as in a Frame)."""
        return {"kinds": self.kinds.tolist(), "offsets": self.offsets.tolist(),
                "vertices": _enc(self.vertices), "sizes": _enc(self.sizes), "colors": self.colors.tolist(),
                "filled": self.filled.tolist(), "texts": list(self.texts)}

    @classmethod
    def from_dict(cls, d: Any) -> Annotations:
        """Inverse of :meth:`to_dict`; ValueError naming what is wrong for malformed data."""
        if not isinstance(d, dict):
            raise ValueError(f"annotations must be a dict, got {type(d).__name__}")
        try:
            return cls(kinds=np.asarray(d["kinds"], dtype=np.int64), offsets=np.asarray(d["offsets"], dtype=np.int64),
                       vertices=_dec(d["vertices"]).reshape(-1, 2), sizes=_dec(d["sizes"]),
                       colors=np.asarray(d["colors"], dtype=np.int64).reshape(-1, 4).clip(0, 255),
                       filled=np.asarray(d["filled"], dtype=bool), texts=tuple(d["texts"]))
        except KeyError as exc:
            raise ValueError(f"annotations are missing field {exc.args[0]!r}") from None
        except (TypeError, ValueError) as exc:
            raise ValueError(f"annotations: {exc}") from None


EMPTY = Annotations()


def _enc(a: NDArray[np.float64]) -> list[Any]:
    if np.all(np.isfinite(a)):
        return a.tolist()
    obj = a.astype(object)
    bad = ~np.isfinite(a)
    obj[bad] = ["NaN" if math.isnan(v) else ("Infinity" if v > 0 else "-Infinity") for v in a[bad]]
    return list(obj.tolist())


def _dec(data: Any) -> NDArray[np.float64]:
    arr = np.asarray(data, dtype=object)
    flat = [float(str(v).replace("Infinity", "inf")) if isinstance(v, str) else float(v) for v in arr.reshape(-1)]
    return np.asarray(flat, dtype=float).reshape(arr.shape) if flat else np.zeros(arr.shape)


# ---------------------------------------------------------------------------- the caps
@dataclass(frozen=True)
class AnnotationReport:
    """What :func:`sanitize` changed in one batch (counts of primitives)."""

    given: int = 0
    kept: int = 0
    non_finite: int = 0
    clipped_to_arena: int = 0
    clipped_size: int = 0
    cut_text: int = 0
    over_primitives: int = 0
    over_vertices: int = 0
    over_text: int = 0

    @property
    def changed(self) -> bool:
        """True when anything was refused, dropped, cut or clipped."""
        return any((self.non_finite, self.clipped_to_arena, self.clipped_size, self.cut_text,
                    self.over_primitives, self.over_vertices, self.over_text))

    @property
    def warnings(self) -> int:
        """Number of things that went wrong (each kind of change counts once)."""
        return sum(1 for n in (self.non_finite, self.clipped_to_arena, self.clipped_size, self.cut_text,
                               self.over_primitives, self.over_vertices, self.over_text) if n)

    def messages(self, limits: AnnotationLimits = DEFAULT_LIMITS) -> list[str]:
        """One sentence per kind of change, naming the cap."""
        out = []
        if self.non_finite:
            out.append(f"annotations: {self.non_finite} primitive(s) with NaN/inf coordinates or size refused")
        if self.clipped_to_arena:
            out.append(f"annotations: {self.clipped_to_arena} primitive(s) reaching outside the arena clipped to it")
        if self.clipped_size:
            out.append(f"annotations: {self.clipped_size} radius/size/width(s) above the cap "
                       f"({'the arena diagonal' if limits.max_size is None else f'{limits.max_size} m'}) clipped")
        if self.cut_text:
            out.append(f"annotations: {self.cut_text} text(s) longer than {limits.max_text} characters cut")
        if self.over_primitives:
            out.append(f"annotations: {self.over_primitives} primitive(s) over the cap of {limits.max_primitives} "
                       "per tick dropped (use fewer, or lifetimes/keys so old ones go)")
        if self.over_vertices:
            out.append(f"annotations: {self.over_vertices} primitive(s) over the cap of {limits.max_vertices} "
                       "vertices per tick dropped")
        if self.over_text:
            out.append(f"annotations: {self.over_text} text(s) over the cap of {limits.max_total_text} characters "
                       "per tick dropped")
        return out


def clean_text(text: str, max_text: int) -> tuple[str, bool]:
    """``text`` cut at ``max_text`` characters (with "…") and with control characters as spaces; and
    whether it was cut. Looks at no more than ``max_text + 1`` characters of ``text``."""
    head = text[:max_text + 1]
    cut = len(head) > max_text
    if cut:
        head = head[:max(max_text - 1, 0)] + "…"
    if not head.isprintable():
        head = "".join(c if c.isprintable() else " " for c in head)
    return head, cut


def sanitize(ann: Annotations, bounds: Bounds,
             limits: AnnotationLimits = DEFAULT_LIMITS) -> tuple[Annotations, AnnotationReport]:
    """``ann`` within the caps of ``limits`` on the arena ``bounds`` (module docstring) and what was changed.

    In order: primitives past ``max_primitives`` are dropped; then those with a non-finite vertex or size
    (or a negative size) are refused; then primitives past ``max_vertices`` vertices and texts past
    ``max_total_text`` characters are dropped; vertices are clipped into the arena, sizes to the cap,
    texts cut to ``max_text``. Never mutates ``ann``; returns ``ann`` itself when nothing needed changing.
    """
    b = Bounds.of(bounds)
    given = len(ann)
    if not given:
        return ann, AnnotationReport()
    over_p = max(0, given - limits.max_primitives)
    if over_p:
        ann = ann.select(np.arange(given) < limits.max_primitives)
    counts = ann.vertex_counts()
    bad_vertex = ~np.isfinite(ann.vertices).all(axis=1)
    bad = np.zeros(len(ann), dtype=bool)
    if bad_vertex.any():
        bad |= np.add.reduceat(bad_vertex.astype(np.int64), ann.offsets[:-1]) > 0
    bad |= ~np.isfinite(ann.sizes) | (ann.sizes < 0)
    keep = ~bad
    ends = np.cumsum(np.where(keep, counts, 0))
    over_v_mask = keep & (ends > limits.max_vertices)
    keep &= ~over_v_mask
    is_text = ann.kinds == TEXT
    lengths = np.fromiter((min(len(t), limits.max_text) for t in ann.texts), dtype=np.int64, count=len(ann))
    text_ends = np.cumsum(np.where(keep & is_text, lengths, 0))
    over_t_mask = keep & is_text & (text_ends > limits.max_total_text)
    keep &= ~over_t_mask
    ann = ann.select(keep)
    verts = ann.vertices
    clipped = np.clip(verts, [b.x_min, b.y_min], [b.x_max, b.y_max])
    moved = (clipped != verts).any(axis=1)
    n_clipped = int((np.add.reduceat(moved.astype(np.int64), ann.offsets[:-1]) > 0).sum()) if len(ann) and moved.any() else 0
    cap = limits.size_cap(b)
    big = ann.sizes > cap
    texts, n_cut = list(ann.texts), 0
    for i in np.flatnonzero(ann.kinds == TEXT):
        texts[i], cut = clean_text(texts[i], limits.max_text)
        n_cut += cut
    report = AnnotationReport(given=given, kept=len(ann), non_finite=int(bad.sum()), clipped_to_arena=n_clipped,
                              clipped_size=int(big.sum()), cut_text=n_cut, over_primitives=over_p,
                              over_vertices=int(over_v_mask.sum()), over_text=int(over_t_mask.sum()))
    if not report.changed and tuple(texts) == ann.texts:
        return ann, report  # nothing to change: the batch itself
    out = Annotations(kinds=ann.kinds, offsets=ann.offsets, vertices=clipped, sizes=np.minimum(ann.sizes, cap),
                      colors=ann.colors, filled=ann.filled, texts=tuple(texts))
    return out, report
