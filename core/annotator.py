"""The drawing API of an experiment: ``arena.draw.circle((0, 0), 0.1, color="red", seconds=2)``.

An :class:`Annotator` holds what an experiment has drawn and hands, once per tick, the primitives alive in
that tick (:meth:`Annotator.collect`) as one :class:`~swarmdeck.core.annotations.Annotations` within the caps
(:func:`~swarmdeck.core.annotations.sanitize`). Everything is in arena metres. Every drawing call takes

* ``color``: a name (``"red"``, matplotlib's one-letter ``"r"``, …), ``"#rgb"``, ``"#rrggbb"``,
  ``"#rrggbbaa"``, or a tuple of 3 or 4 numbers — floats in [0, 1] (matplotlib's convention) or integers
  0–255; ``alpha`` (0–1) overrides the colour's own;
* a lifetime: ``ticks=k`` (drawn in the next k ticks), ``seconds=s`` (drawn while the run's time is within s
  of when it was drawn), both (whichever ends first), or neither: drawn until :meth:`~Annotator.clear` or
  :meth:`~Annotator.remove`;
* ``key``: a name; drawing again with the same key replaces what the key drew before (the usual way to move
  a marker every step without piling up copies).

Caps (:class:`~swarmdeck.core.annotations.AnnotationLimits`): past ``max_primitives`` alive primitives a call
draws only what fits and the rest is dropped and counted, without converting it (a million points cost
milliseconds); texts are cut at ``max_text`` characters before they are stored. Every cap hit is counted in
:attr:`Annotator.warnings` and described in :attr:`Annotator.messages` (the Arena puts those in its events).
Bad arguments (wrong shapes, an unknown colour) raise ValueError naming the argument.
"""
from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.annotations import (
    CIRCLE,
    DEFAULT_LIMITS,
    EMPTY,
    POINT,
    POLYGON,
    POLYLINE,
    TEXT,
    AnnotationLimits,
    AnnotationReport,
    Annotations,
    clean_text,
    sanitize,
)
from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds

#: colour names a drawing call understands (RGB 0–255): matplotlib's one-letter codes and a few common names
COLOR_NAMES: dict[str, tuple[int, int, int]] = {
    "b": (31, 119, 180), "g": (44, 160, 44), "r": (214, 39, 40), "c": (23, 190, 207), "m": (227, 119, 194),
    "y": (188, 189, 34), "k": (0, 0, 0), "w": (255, 255, 255),
    "black": (0, 0, 0), "white": (255, 255, 255), "red": (214, 39, 40), "green": (44, 160, 44),
    "blue": (31, 119, 180), "orange": (255, 127, 14), "purple": (148, 103, 189), "brown": (140, 86, 75),
    "pink": (227, 119, 194), "gray": (127, 127, 127), "grey": (127, 127, 127), "olive": (188, 189, 34),
    "cyan": (23, 190, 207), "magenta": (227, 119, 194), "yellow": (255, 215, 0),
}
#: what is drawn when no colour is given
DEFAULT_COLOR = (0, 0, 0, 255)
#: a point's radius when none is given, m
POINT_RADIUS = 0.015
#: a line's width when none is given, m
LINE_WIDTH = 0.01
#: a text's height when none is given, m
TEXT_HEIGHT = 0.06
_MESSAGES_KEPT = 50
#: s of run time before the same kind of cap hit is said again (it is counted every time)
REPEAT_S = 1.0


def parse_color(color: Any, alpha: float | None = None) -> NDArray[np.uint8]:
    """``color`` (module docstring) as (4,) uint8 RGBA; ValueError naming the colour when it is not one."""
    if isinstance(color, str) and alpha is None:
        return _named(color).copy()
    return _parse_color(color, alpha)


@lru_cache(maxsize=256)
def _named(color: str) -> NDArray[np.uint8]:
    return _parse_color(color, None)


def _parse_color(color: Any, alpha: float | None) -> NDArray[np.uint8]:
    rgba: tuple[float, ...]
    if color is None:
        rgba = tuple(float(c) for c in DEFAULT_COLOR)
    elif isinstance(color, str):
        s = color.strip().lower()
        if s in COLOR_NAMES:
            rgba = (*map(float, COLOR_NAMES[s]), 255.0)
        elif s.startswith("#") and len(s) in (4, 7, 9):
            h = s[1:]
            if len(h) == 3:
                h = "".join(c * 2 for c in h)
            try:
                hexes = [int(h[i:i + 2], 16) for i in range(0, len(h), 2)]
            except ValueError:
                raise ValueError(f"colour {color!r} is not a hex colour #rgb, #rrggbb or #rrggbbaa") from None
            rgba = tuple(float(v) for v in (*hexes, 255)[:4])
        else:
            raise ValueError(f"unknown colour {color!r}: use one of {', '.join(sorted(COLOR_NAMES))}, "
                             "a hex colour '#rrggbb' or an (r, g, b[, a]) tuple")
    else:
        try:
            floats = [float(c) for c in color]
        except (TypeError, ValueError):
            raise ValueError(f"colour {color!r} is not a name, a hex string or an (r, g, b[, a]) tuple") from None
        if len(floats) not in (3, 4) or not all(math.isfinite(v) for v in floats):
            raise ValueError(f"colour {color!r} must have 3 or 4 finite components")
        integers = all(isinstance(c, (int, np.integer)) for c in color) and any(v > 1 for v in floats)
        scale = 1.0 if integers else 255.0
        rgba = tuple([v * scale for v in floats] + ([] if len(floats) == 4 else [255.0]))
    if alpha is not None:
        if not (isinstance(alpha, (int, float, np.number)) and 0.0 <= float(alpha) <= 1.0):
            raise ValueError(f"alpha must be a number in [0, 1], got {alpha!r}")
        rgba = (*rgba[:3], 255.0 * float(alpha))
    return np.clip(np.round(np.asarray(rgba, dtype=float)), 0, 255).astype(np.uint8)


@dataclass
class _Group:
    """What one drawing call drew, and how long it lives."""

    ann: Annotations
    key: str | None
    ticks_left: int | None
    until: float | None


class Annotator:
    """What an experiment draws (module docstring). Not thread-safe: one experiment draws from one thread.

    Args:
        bounds: the arena (x_min, x_max, y_min, y_max), m — what coordinates are clipped to.
        limits: the caps.
    """

    def __init__(self, bounds: Bounds | tuple[float, float, float, float] = DEFAULT_BOUNDS,
                 limits: AnnotationLimits = DEFAULT_LIMITS) -> None:
        self.bounds = Bounds.of(bounds)
        self.limits = limits
        self._groups: list[_Group] = []
        self._alive = 0
        self._time = 0.0
        self._dropped = 0
        self.warnings = 0
        """cap hits so far (one per tick and kind of cap hit, and one per text cut)"""
        self.messages: deque[str] = deque(maxlen=_MESSAGES_KEPT)
        """the most recent cap messages"""
        self.last_report = AnnotationReport()
        self._new: list[str] = []
        self._said: dict[str, float] = {}
        self._cache: tuple[tuple[int, ...], Annotations, list[_Group]] | None = None

    # ---------------------------------------------------------------- lifetime bookkeeping
    def _warn(self, message: str) -> None:
        """Count a cap hit; say it (:attr:`messages`, :meth:`take_messages`) unless the same kind of hit was
        said less than :data:`REPEAT_S` s of run time ago (a script that hits a cap every tick is one line a
        second, not thirty)."""
        self.warnings += 1
        kind = message.split(" ", 2)[-1]
        if self._time - self._said.get(kind, -math.inf) < REPEAT_S:
            return
        self._said[kind] = self._time
        self.messages.append(message)
        if len(self._new) < _MESSAGES_KEPT:
            self._new.append(message)

    def take_messages(self) -> list[str]:
        """The cap messages since the last call (at most the 50 first), for a log or the run's events."""
        new, self._new = self._new, []
        return new

    def _room(self, wanted: int) -> int:
        """How many of ``wanted`` new primitives fit under ``max_primitives``; counts and says the rest."""
        room = max(0, self.limits.max_primitives - self._alive)
        if wanted > room:
            self._dropped += wanted - room  # said once, at the next collect
        return min(wanted, room)

    def _add(self, ann: Annotations, key: str | None, ticks: int | None, seconds: float | None) -> None:
        if ticks is not None and (not isinstance(ticks, (int, np.integer)) or ticks < 1):
            raise ValueError(f"ticks must be a positive integer, got {ticks!r}")
        if seconds is not None and not (isinstance(seconds, (int, float, np.number)) and float(seconds) > 0
                                        and math.isfinite(float(seconds))):
            raise ValueError(f"seconds must be a positive number, got {seconds!r}")
        if key is not None:
            self.remove(key)
        if not len(ann):
            return
        until = None if seconds is None else self._time + float(seconds)
        self._groups.append(_Group(ann, None if key is None else str(key), ticks, until))
        self._alive += len(ann)

    def remove(self, key: str) -> None:
        """Remove what was drawn with ``key`` (nothing when nothing was)."""
        kept = [g for g in self._groups if g.key != str(key)]
        if len(kept) != len(self._groups):
            self._groups = kept
            self._alive = sum(len(g.ann) for g in kept)

    def clear(self) -> None:
        """Remove everything drawn."""
        self._groups = []
        self._alive = 0

    @property
    def alive(self) -> int:
        """Primitives drawn and not yet expired."""
        return self._alive

    def collect(self, time: float) -> Annotations:
        """The primitives to draw in the tick at ``time`` (s, the run's clock), within the caps; then ages them
        by one tick (a ``ticks=k`` primitive is in k collects; a ``seconds=s`` one in those at times ≤ its
        drawing time + s). Call once per tick."""
        self._time = float(time)
        if self._dropped:
            self._warn(f"annotations: {self._dropped} primitive(s) over the cap of {self.limits.max_primitives} "
                       "alive at once dropped (give them a lifetime or a key, or clear())")
            self._dropped = 0
        live = [g for g in self._groups if g.until is None or self._time <= g.until + 1e-9]
        key = tuple(id(g) for g in live)
        if self._cache is not None and self._cache[0] == key:  # the same drawing as the last tick: checked already
            out, report = self._cache[1], AnnotationReport(given=len(self._cache[1]), kept=len(self._cache[1]))
        else:
            out, report = sanitize(Annotations.concat([g.ann for g in live]), self.bounds, self.limits)
            self._cache = (key, out, live)
        self.last_report = report
        if report.changed:
            for message in report.messages(self.limits):
                self._warn(message)
        for g in live:
            if g.ticks_left is not None:
                g.ticks_left -= 1
        self._groups = [g for g in live if g.ticks_left is None or g.ticks_left > 0]
        self._alive = sum(len(g.ann) for g in self._groups)
        return out

    # ---------------------------------------------------------------- the drawing calls
    def _batch(self, kind: int, vertices: NDArray[np.float64], counts: NDArray[np.int64], sizes: Any, color: Any,
               alpha: float | None, filled: bool, texts: tuple[str, ...] | None = None) -> Annotations:
        p = len(counts)
        rgba = parse_color(color, alpha)
        size_arr = np.array(np.broadcast_to(np.asarray(sizes, dtype=float), (p,)), dtype=np.float64)
        offsets = np.zeros(p + 1, dtype=np.int64)
        np.cumsum(counts, out=offsets[1:])
        return Annotations._unchecked(np.full(p, kind, dtype=np.uint8), offsets,
                                      np.array(vertices, dtype=np.float64).reshape(-1, 2), size_arr,
                                      np.tile(rgba, (p, 1)), np.full(p, bool(filled)),
                                      texts if texts is not None else ("",) * p)

    def _many(self, xy: Any, name: str) -> NDArray[np.float64]:
        """(M, 2) rows of ``xy`` ((2,) or (M, 2)) that fit under the cap — cut before converting, so a
        million rows cost no more than the rows kept."""
        if isinstance(xy, np.ndarray):
            many = xy.ndim == 2
        else:
            try:
                many = len(xy) > 0 and np.ndim(xy[0]) > 0
            except TypeError:
                raise ValueError(f"{name} must be (x, y) or an (M, 2) array of points in metres") from None
        m = self._room(len(xy) if many else 1)
        return self._xy(xy[:m] if many else xy, name)[:m]

    def _xy(self, xy: ArrayLike, name: str) -> NDArray[np.float64]:
        arr = np.asarray(xy, dtype=float)
        if arr.ndim == 1 and arr.shape == (2,):
            arr = arr[None]
        if arr.ndim != 2 or arr.shape[1] != 2:
            raise ValueError(f"{name} must be (x, y) or an (M, 2) array of points in metres, got shape {arr.shape}")
        return arr

    def _sizes(self, sizes: Any, m: int, name: str) -> Any:
        if np.ndim(sizes) == 0:
            return float(sizes)
        arr = np.asarray(sizes, dtype=float).reshape(-1)
        if len(arr) < m:
            raise ValueError(f"{name} has {len(arr)} values for {m} primitives")
        return arr[:m]

    def points(self, xy: ArrayLike, *, radius: Any = POINT_RADIUS, color: Any = None, alpha: float | None = None,
               ticks: int | None = None, seconds: float | None = None, key: str | None = None) -> None:
        """Dots at ``xy`` ((2,) or (M, 2), m) of ``radius`` m (one or (M,))."""
        arr = self._many(xy, "points")
        self._add(self._batch(POINT, arr, np.ones(len(arr), dtype=np.int64), self._sizes(radius, len(arr), "radius"),
                              color, alpha, True), key, ticks, seconds)

    point = points

    def circles(self, centres: ArrayLike, radius: Any, *, color: Any = None, alpha: float | None = None,
                fill: bool = False, width: float = LINE_WIDTH, ticks: int | None = None, seconds: float | None = None,
                key: str | None = None) -> None:
        """Circles round ``centres`` ((2,) or (M, 2), m) of ``radius`` m (one or (M,)); ``fill`` or an outline
        ``width`` m wide (the outline's width is not stored separately: a circle's size is its radius)."""
        arr = self._many(centres, "centres")
        self._add(self._batch(CIRCLE, arr, np.ones(len(arr), dtype=np.int64), self._sizes(radius, len(arr), "radius"),
                              color, alpha, fill), key, ticks, seconds)

    circle = circles

    def polyline(self, xy: ArrayLike, *, color: Any = None, alpha: float | None = None, width: float = LINE_WIDTH,
                 closed: bool = False, ticks: int | None = None, seconds: float | None = None,
                 key: str | None = None) -> None:
        """A polyline through ``xy`` (V ≥ 2, 2) m, ``width`` m wide (``closed``: back to the first vertex)."""
        if not self._room(1):
            return
        arr = self._xy(xy, "polyline")[: self.limits.max_vertices]
        if len(arr) < 2:
            raise ValueError(f"a polyline needs at least 2 points, got {len(arr)}")
        if closed:
            arr = np.vstack((arr, arr[:1]))
        self._add(self._batch(POLYLINE, arr, np.array([len(arr)]), width, color, alpha, False), key, ticks, seconds)

    def line(self, start: ArrayLike, end: ArrayLike, **kwargs: Any) -> None:
        """A segment from ``start`` to ``end`` ((2,), m); keywords as :meth:`polyline`."""
        self.polyline(np.vstack((np.asarray(start, dtype=float).reshape(2), np.asarray(end, dtype=float).reshape(2))),
                      **kwargs)

    def lines(self, segments: Any, *, color: Any = None, alpha: float | None = None, width: float = LINE_WIDTH,
              ticks: int | None = None, seconds: float | None = None, key: str | None = None) -> None:
        """Segments ``(M, 2, 2)`` m (start, end), one primitive each."""
        m = self._room(len(segments) if hasattr(segments, "__len__") else 0)
        raw = np.asarray(segments[:m] if hasattr(segments, "__getitem__") else segments, dtype=float)
        if raw.size and (raw.ndim != 3 or raw.shape[1:] != (2, 2)):
            raise ValueError(f"segments must have shape (M, 2, 2), got {raw.shape}")
        arr = raw.reshape(-1, 2)
        self._add(self._batch(POLYLINE, arr, np.full(m, 2, dtype=np.int64), width, color, alpha, False),
                  key, ticks, seconds)

    def polygon(self, xy: ArrayLike, *, color: Any = None, alpha: float | None = None, fill: bool = True,
                width: float = LINE_WIDTH, ticks: int | None = None, seconds: float | None = None,
                key: str | None = None) -> None:
        """A polygon with vertices ``xy`` (V ≥ 3, 2) m, filled or (``fill=False``) an outline ``width`` m wide."""
        if not self._room(1):
            return
        arr = self._xy(xy, "polygon")[: self.limits.max_vertices]
        if len(arr) < 3:
            raise ValueError(f"a polygon needs at least 3 vertices, got {len(arr)}")
        self._add(self._batch(POLYGON, arr, np.array([len(arr)]), width, color, alpha, fill), key, ticks, seconds)

    def text(self, xy: ArrayLike, text: str, *, height: float = TEXT_HEIGHT, color: Any = None,
             alpha: float | None = None, ticks: int | None = None, seconds: float | None = None,
             key: str | None = None) -> None:
        """``text`` centred on ``xy`` ((2,), m), ``height`` m tall; cut at the cap's ``max_text`` characters."""
        if not self._room(1):
            return
        body, cut = clean_text(str(text) if not isinstance(text, str) else text, self.limits.max_text)
        if cut:
            self._warn(f"annotations: a text longer than {self.limits.max_text} characters cut")
        arr = self._xy(xy, "text position")
        if len(arr) != 1:
            raise ValueError(f"text position must be one point (x, y), got {len(arr)}")
        self._add(self._batch(TEXT, arr, np.ones(1, dtype=np.int64), height, color, alpha, False, (body,)),
                  key, ticks, seconds)

    def add(self, ann: Annotations, *, ticks: int | None = None, seconds: float | None = None,
            key: str | None = None) -> None:
        """A ready batch (e.g. the rps figure's artists, or what a sandboxed script sent), as far as it fits."""
        m = self._room(len(ann))
        if m < len(ann):
            ann = ann.select(np.arange(len(ann)) < m)
        self._add(ann, key, ticks, seconds)


class RobotDrawing:
    """One robot's pen on a shared :class:`Annotator` (the decentralised style's ``view.draw``): the same
    drawing calls, each robot's keys its own (robot 3's ``key="goal"`` does not replace robot 5's), and
    :meth:`clear` clears only what this robot drew with a key. Everything a robot draws is drawn on the one
    arena (annotations are global, in arena metres): a robot's drawing is not a message to the others."""

    _CALLS = ("points", "point", "circles", "circle", "polyline", "line", "lines", "polygon", "text")

    def __init__(self, annotator: Annotator, robot: int) -> None:
        self._annotator = annotator
        self._prefix = f"robot {int(robot)}: "
        self._keys: set[str] = set()

    def __getattr__(self, name: str) -> Any:
        if name not in self._CALLS:
            raise AttributeError(f"a robot's drawing has {', '.join(self._CALLS)}, remove and clear; not {name!r}")
        call = getattr(self._annotator, name)

        def draw(*args: Any, key: str | None = None, **kwargs: Any) -> None:
            if key is not None:
                key = self._prefix + str(key)
                self._keys.add(key)
            call(*args, key=key, **kwargs)

        return draw

    def remove(self, key: str) -> None:
        """Remove what this robot drew with ``key``."""
        self._annotator.remove(self._prefix + str(key))

    def clear(self) -> None:
        """Remove what this robot drew with a key (what it drew with a lifetime expires by itself)."""
        for key in self._keys:
            self._annotator.remove(key)
        self._keys.clear()


def robot_drawing(annotator: Annotator, robot: int) -> RobotDrawing:
    """Robot ``robot``'s pen on ``annotator`` (:class:`RobotDrawing`)."""
    return RobotDrawing(annotator, robot)


__all__ = ["COLOR_NAMES", "DEFAULT_COLOR", "EMPTY", "Annotator", "RobotDrawing", "parse_color", "robot_drawing"]
