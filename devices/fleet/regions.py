"""Regions of one floor: several experiments at once, each in its own rectangle (issue 30.1).

A :class:`RegionLayout` divides the floor (the arena rectangle, floor frame: origin at the floor's
centre, m) into named, disjoint axis-aligned rectangles. A job placed in a region sees that region as
its whole arena: its bounds are the region's, centred on its own origin (:attr:`Region.origin`, the
region's centre in the floor frame), its robots are 0…N−1 (:mod:`swarmdeck.devices.fleet.floor`). The
floor's one barrier holds every robot inside its region's rectangle (per-robot wall rows,
:func:`swarmdeck.safety.constraints.wall_rows`): with the wall margin D_s/2 on the look-ahead points,
two robots in different regions keep their points at least D_s apart, so they never touch.

A region docks on the charger slots of the floor walls it declares (``chargers``): the slots of those
strips whose docks lie inside it. The layout is refused (ValueError naming the regions) when

* a region leaves the floor, or two regions overlap (touching edges are fine);
* a region is narrower or lower than :data:`MIN_REGION_SIDE` (one robot's body plus the barrier's wall
  margin D_s/2 on each side);
* a region declares a strip on a floor wall it does not reach, or has no slot of it inside, or the
  approach poses of its slots leave it (its robots would dock through another region);
* a region covers slots of a strip another region docks on (and does not declare it itself).

A slot belongs to a region when its docked robot's look-ahead point lies D_s/2 inside it (the barrier's wall
margin); a slot on the edge between two regions belongs to neither and is not used.

Capacity (:meth:`RegionLayout.capacity`): the robots a region holds at once — the start-pose lattice
inside it (clear of its chargers' approach area), and at most its charger slots when it has chargers.

**Regions allocated per job** (:meth:`RegionLayout.guillotine`, ``--arena NAME=sim,regions=auto:4x2``): the floor
as a tree of guillotine cuts — the whole floor, cut in two across its longer side, each half cut again, down to a
``COLS × ROWS`` grid of leaves. Every node of the tree is a region (``nested``: a region may lie inside another,
never partly over it); robots are parked in the leaves. A job gets the smallest region that holds its robots, and
a region is free only when no region above or below it in the tree runs a job (:meth:`RegionLayout.conflicts`:
a buddy allocator): small jobs share the floor one leaf each, a job asking for more robots than a leaf holds gets
a half, a quarter, … or the whole floor — so the floor is split into as many regions as what the queue asks fits.
"""
from __future__ import annotations

import re
from collections.abc import Collection, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds, check_bounds
from swarmdeck.core.constants import LOOKAHEAD, ROBOT_DIAMETER, SAFETY_DISTANCE
from swarmdeck.core.kinematics import lookahead_points
from swarmdeck.devices.chargers import WALLS, ChargerLayout
from swarmdeck.devices.initial_conditions import max_robots

FloatArray = NDArray[np.float64]

#: The smallest side of a region, m: one robot's body (Ø 0.11 m) plus the barrier's wall margin D_s/2 on
#: each side (REFERENCE.md §1, §3): a region smaller than this cannot hold a robot inside its walls.
MIN_REGION_SIDE: float = ROBOT_DIAMETER + SAFETY_DISTANCE
_NAME = re.compile(r"^[A-Za-z0-9_-]{1,40}$")
_TOL = 1e-9  # m: rectangles closer than this count as touching, not overlapping


@dataclass(frozen=True)
class Region:
    """One region of the floor.

    Attributes:
        name: unique in its layout (letters, digits, ``_``, ``-``; at most 40).
        bounds: ``(x_min, x_max, y_min, y_max)`` in the floor frame, m.
        chargers: floor walls (``"bottom"``, ``"top"``, ``"left"``, ``"right"``) whose charger strips its
            robots dock on (the slots inside it).
    """

    name: str
    bounds: Bounds
    chargers: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not _NAME.match(self.name):
            raise ValueError(f"region name {self.name!r}: use 1-40 letters, digits, '_' or '-'")
        object.__setattr__(self, "bounds", check_bounds(self.bounds, f"region {self.name}: bounds"))
        chargers = (self.chargers,) if isinstance(self.chargers, str) else tuple(self.chargers)
        bad = [w for w in chargers if w not in WALLS]
        if bad or len(set(chargers)) != len(chargers):
            raise ValueError(f"region {self.name}: chargers must be distinct walls from {WALLS}, got {chargers!r}")
        object.__setattr__(self, "chargers", chargers)

    @property
    def origin(self) -> tuple[float, float]:
        """The region's centre in the floor frame, m: the script's ``(0, 0)``."""
        return self.bounds.centre

    @property
    def local_bounds(self) -> Bounds:
        """The region as its job sees it: the same rectangle centred on ``(0, 0)``, m (rounded to 1 nm, so that
        regions of one size have equal bounds whatever the rounding of their floor-frame edges)."""
        hw, hh = round(self.bounds.width / 2, 9), round(self.bounds.height / 2, 9)
        return Bounds(-hw, hw, -hh, hh)

    def to_local(self, poses: ArrayLike) -> FloatArray:
        """Floor-frame ``(..., 2|3)`` positions or poses as region-local ones (a translation; θ unchanged)."""
        out = np.array(poses, dtype=float)
        out[..., 0] -= self.origin[0]
        out[..., 1] -= self.origin[1]
        return out

    def to_floor(self, poses: ArrayLike) -> FloatArray:
        """Region-local ``(..., 2|3)`` positions or poses in the floor frame (a translation; θ unchanged)."""
        out = np.array(poses, dtype=float)
        out[..., 0] += self.origin[0]
        out[..., 1] += self.origin[1]
        return out

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "bounds": list(self.bounds), "chargers": list(self.chargers)}


def _overlap(a: Bounds, b: Bounds) -> bool:
    return (min(a.x_max, b.x_max) - max(a.x_min, b.x_min) > _TOL
            and min(a.y_max, b.y_max) - max(a.y_min, b.y_min) > _TOL)


def _inside(inner: Bounds, outer: Bounds) -> bool:
    return (inner.x_min >= outer.x_min - _TOL and inner.x_max <= outer.x_max + _TOL
            and inner.y_min >= outer.y_min - _TOL and inner.y_max <= outer.y_max + _TOL)


def _nested(a: Bounds, b: Bounds) -> bool:
    """One of the rectangles lies wholly inside the other."""
    return _inside(a, b) or _inside(b, a)


def _grid_lines(floor: Bounds, columns: int, rows: int, charger_layout: ChargerLayout | None
                ) -> tuple[Bounds, ChargerLayout, NDArray[np.float64], NDArray[np.float64]]:
    """A ``columns`` × ``rows`` grid of ``floor``: the checked floor, its charger layout (``charger_layout``, else
    the floor's default) and the grid lines' x (columns + 1) and y (rows + 1), m; ValueError for an empty grid."""
    if columns < 1 or rows < 1:
        raise ValueError(f"regions: a grid needs at least 1 column and 1 row, got {columns} x {rows}")
    floor = check_bounds(floor, "regions: floor")
    chargers = charger_layout if charger_layout is not None else ChargerLayout(bounds=floor)
    return (floor, chargers, np.linspace(floor.x_min, floor.x_max, columns + 1),
            np.linspace(floor.y_min, floor.y_max, rows + 1))


def _reaches(region: Bounds, floor: Bounds, wall: str) -> bool:
    k = WALLS.index(wall)
    return abs((region.y_min, region.y_max, region.x_min, region.x_max)[k]
               - (floor.y_min, floor.y_max, floor.x_min, floor.x_max)[k]) <= _TOL


@dataclass(frozen=True)
class RegionLayout:
    """The floor divided into regions (module docstring); validated on construction.

    Attributes:
        floor: the whole floor, m.
        regions: the regions (at least one).
        charger_layout: the floor's charger strips (default: a :class:`ChargerLayout` of ``floor``).
        nested: a region may lie wholly inside another (the tree of :meth:`guillotine`; two such regions never run
            jobs at once: :meth:`conflicts`); partial overlaps are refused either way.
    """

    floor: Bounds = DEFAULT_BOUNDS
    regions: tuple[Region, ...] = ()
    charger_layout: ChargerLayout | None = field(default=None, compare=False)
    nested: bool = False

    def __post_init__(self) -> None:
        floor = check_bounds(self.floor, "regions: floor")
        object.__setattr__(self, "floor", floor)
        regions = tuple(self.regions)
        object.__setattr__(self, "regions", regions)
        if not regions:
            raise ValueError("regions: the layout needs at least one region")
        names = [r.name for r in regions]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ValueError(f"regions: names must be unique, {', '.join(dup)} repeated")
        chargers = self.charger_layout if self.charger_layout is not None else ChargerLayout(bounds=floor)
        object.__setattr__(self, "charger_layout", chargers)
        for r in regions:
            b = r.bounds
            if b.x_min < floor.x_min - _TOL or b.x_max > floor.x_max + _TOL or b.y_min < floor.y_min - _TOL \
                    or b.y_max > floor.y_max + _TOL:
                raise ValueError(f"region {r.name}: {tuple(b)} leaves the floor {tuple(floor)}")
            if min(b.width, b.height) < MIN_REGION_SIDE:
                raise ValueError(f"region {r.name}: {b.width:.3f} m x {b.height:.3f} m is smaller than one robot's "
                                 f"footprint with the barrier's wall margins ({MIN_REGION_SIDE:.2f} m a side)")
        for k, first in enumerate(regions):
            for second in regions[k + 1:]:  # a handful of regions, once per layout
                if _overlap(first.bounds, second.bounds) and not (self.nested and _nested(first.bounds,
                                                                                          second.bounds)):
                    raise ValueError(f"regions {first.name} and {second.name} overlap: {tuple(first.bounds)} and "
                                     f"{tuple(second.bounds)}")
        self._check_chargers(chargers)

    def _check_chargers(self, chargers: ChargerLayout) -> None:
        walls, approach = chargers.slot_walls(), chargers.approach_poses()
        declared = {w: [r.name for r in self.regions if w in r.chargers] for w in WALLS}
        for r in self.regions:
            inside = self._holds_slot(r, chargers)
            for w in r.chargers:
                if not _reaches(r.bounds, self.floor, w):
                    raise ValueError(f"region {r.name}: declares the {w} charger strip but does not reach the "
                                     f"floor's {w} wall")
                mine = inside & (walls == WALLS.index(w))
                if not mine.any():
                    raise ValueError(f"region {r.name}: has no slot of the {w} charger strip inside it")
                out = mine & ~r.bounds.contains(approach)
                if out.any():
                    raise ValueError(f"region {r.name}: the approach area of its {w} charger slots leaves the "
                                     f"region (robots would dock through another region); make it deeper than "
                                     f"{chargers.dock_depth + chargers.approach_distance + chargers.approach_stagger:.2f} m")
            for w in WALLS:
                others = [n for n in declared[w] if n != r.name
                          and not (self.nested and _nested(r.bounds, self.region(n).bounds))]
                if w not in r.chargers and others and (inside & (walls == WALLS.index(w))).any():
                    raise ValueError(f"region {r.name} covers part of the {w} charger strip that region "
                                     f"{others[0]} docks on")

    # ------------------------------------------------------------------ building
    @classmethod
    def from_mapping(cls, data: Mapping[str, Any], floor: Bounds = DEFAULT_BOUNDS,
                     charger_layout: ChargerLayout | None = None) -> RegionLayout:
        """The ``[regions]`` table of an arena config: ``{name: {"bounds": [x0, x1, y0, y1], "chargers": [...]}}``
        (floor-frame m). ValueError naming the region and key that is wrong."""
        if not isinstance(data, Mapping) or not data:
            raise ValueError("[regions] must be a table of regions, e.g. [regions.west] bounds = [-1.6, 0, -1, 1]")
        regions = []
        for name, spec in data.items():
            if not isinstance(spec, Mapping):
                raise ValueError(f"[regions.{name}] must be a table with bounds (and chargers)")
            unknown = sorted(set(spec) - {"bounds", "chargers"})
            if unknown:
                raise ValueError(f"[regions.{name}]: unknown key(s) {', '.join(unknown)} (bounds, chargers)")
            if "bounds" not in spec:
                raise ValueError(f"[regions.{name}]: bounds = [x_min, x_max, y_min, y_max] is missing")
            chargers = spec.get("chargers", ())
            if isinstance(chargers, str) or not isinstance(chargers, (list, tuple)):
                raise ValueError(f"[regions.{name}]: chargers must be a list of walls from {WALLS}")
            regions.append(Region(str(name), check_bounds(spec["bounds"], f"[regions.{name}] bounds"),
                                  tuple(str(w) for w in chargers)))
        return cls(floor, tuple(regions), charger_layout)

    @classmethod
    def grid(cls, floor: Bounds = DEFAULT_BOUNDS, columns: int = 2, rows: int = 1, *,
             charger_layout: ChargerLayout | None = None) -> RegionLayout:
        """``columns`` × ``rows`` equal regions named ``r<row>c<col>`` (from the bottom left), each docking on
        the strips of the floor walls it reaches among those with chargers."""
        floor, chargers, xs, ys = _grid_lines(floor, columns, rows, charger_layout)
        regions = []
        for r in range(rows):  # a handful of cells, once per layout
            for c in range(columns):
                b = Bounds(float(xs[c]), float(xs[c + 1]), float(ys[r]), float(ys[r + 1]))
                walls = tuple(w for w in chargers.walls if _reaches(b, floor, w))
                regions.append(Region(f"r{r}c{c}", b, walls))
        return cls(floor, tuple(regions), chargers)

    @classmethod
    def guillotine(cls, floor: Bounds = DEFAULT_BOUNDS, columns: int = 2, rows: int = 2, *,
                   charger_layout: ChargerLayout | None = None) -> RegionLayout:
        """Regions allocated per job (module docstring): the tree of guillotine cuts of ``floor`` down to a
        ``columns`` × ``rows`` grid of leaves — each node cut in two across its longer side (at the middle grid line
        of that side), leaves named as :meth:`grid`'s (``r<row>c<col>``), the other nodes
        ``r<row0>-<row1>c<col0>-<col1>`` (the grid cells they span) and the whole floor ``all``. Regions are listed
        smallest first (leaves, …, ``all``); ``nested`` is set. Each region docks on the strips of the floor walls
        it reaches."""
        floor, chargers, xs, ys = _grid_lines(floor, columns, rows, charger_layout)
        nodes: list[tuple[int, int, int, int]] = []  # (col0, col1, row0, row1), cells [col0, col1) x [row0, row1)
        todo = [(0, columns, 0, rows)]
        while todo:  # at most 2 × columns × rows nodes, once per layout
            c0, c1, r0, r1 = todo.pop()
            nodes.append((c0, c1, r0, r1))
            wide, high = xs[c1] - xs[c0], ys[r1] - ys[r0]
            if c1 - c0 > 1 and (wide >= high or r1 - r0 == 1):
                m = (c0 + c1) // 2
                todo += [(c0, m, r0, r1), (m, c1, r0, r1)]
            elif r1 - r0 > 1:
                m = (r0 + r1) // 2
                todo += [(c0, c1, r0, m), (c0, c1, m, r1)]
        regions = []
        for c0, c1, r0, r1 in sorted(nodes, key=lambda n: ((n[1] - n[0]) * (n[3] - n[2]), n[2], n[0])):
            b = Bounds(float(xs[c0]), float(xs[c1]), float(ys[r0]), float(ys[r1]))
            name = ("all" if (c0, c1, r0, r1) == (0, columns, 0, rows) else f"r{r0}c{c0}"
                    if (c1 - c0, r1 - r0) == (1, 1) else f"r{r0}-{r1 - 1}c{c0}-{c1 - 1}")
            regions.append(Region(name, b, tuple(w for w in chargers.walls if _reaches(b, floor, w))))
        return cls(floor, tuple(regions), chargers, nested=True)

    # ------------------------------------------------------------------ questions
    @property
    def names(self) -> tuple[str, ...]:
        return tuple(r.name for r in self.regions)

    @property
    def leaves(self) -> tuple[str, ...]:
        """The regions no other region lies inside (every region of a layout that is not ``nested``): where robots
        are parked."""
        return tuple(r.name for r in self.regions
                     if not any(o is not r and _inside(o.bounds, r.bounds) for o in self.regions))

    def conflicts(self, name: str) -> tuple[str, ...]:
        """The other regions that cannot run a job while region ``name`` does: those it lies in or that lie in it
        (none unless ``nested``)."""
        me = self.region(name)
        return tuple(r.name for r in self.regions if r is not me and _overlap(r.bounds, me.bounds))

    def region(self, name: str) -> Region:
        """The region called ``name``; KeyError naming the known ones."""
        for r in self.regions:
            if r.name == name:
                return r
        raise KeyError(f"no region {name!r} (regions: {', '.join(self.names)})")

    def slots(self, name: str) -> NDArray[np.intp]:
        """Indices of the floor's charger slots region ``name`` docks on (its strips' slots inside it)."""
        r, chargers = self.region(name), self._chargers
        mine = self._holds_slot(r, chargers) & np.isin(chargers.slot_walls(),
                                                                  [WALLS.index(w) for w in r.chargers])
        return np.flatnonzero(mine)

    @staticmethod
    def _holds_slot(region: Region, chargers: ChargerLayout) -> NDArray[np.bool_]:
        """``(M,)`` slots whose docked robot lies in ``region`` with the barrier's wall margin (its look-ahead point
        at least D_s/2 inside): a slot on the edge between two regions belongs to neither."""
        return region.bounds.contains(lookahead_points(chargers.dock_poses(), LOOKAHEAD), margin=SAFETY_DISTANCE / 2)

    @property
    def _chargers(self) -> ChargerLayout:
        assert self.charger_layout is not None  # set in __post_init__
        return self.charger_layout

    def start_area(self, name: str) -> Bounds:
        """Where start poses of region ``name``'s jobs may lie (floor frame, m): the region, less its chargers'
        docking and approach area along the walls it docks on."""
        r, c = self.region(name), self._chargers
        inner = c.dock_depth + c.approach_distance
        x0, x1, y0, y1 = r.bounds
        cut = {w: inner if w in r.chargers else 0.0 for w in WALLS}
        return Bounds(x0 + cut["left"], x1 - cut["right"], y0 + cut["bottom"], y1 - cut["top"])

    def capacity(self) -> dict[str, int]:
        """``{region: robots it holds at once}``: the start-pose lattice of its start area, and at most its charger
        slots when it docks on any."""
        out = {}
        for r in self.regions:
            area = self.start_area(r.name)
            space = max_robots(area) if area.width > 0 and area.height > 0 else 0
            out[r.name] = int(min(space, len(self.slots(r.name))) if r.chargers else space)
        return out

    def fit(self, robots: int, busy: Collection[str] = ()) -> Region | None:
        """The smallest free region (not in ``busy``, nor in conflict with one: :meth:`conflicts`) that holds
        ``robots`` robots — by capacity, then name; None when none does now (:meth:`never_fits` says whether one ever
        will)."""
        cap = self.capacity()
        blocked = set(busy).union(*(self.conflicts(n) for n in busy)) if busy else set()
        free = [r for r in self.regions if r.name not in blocked and cap[r.name] >= int(robots)]
        return min(free, key=lambda r: (cap[r.name], r.name)) if free else None

    def never_fits(self, robots: int) -> str | None:
        """Why a job of ``robots`` robots can never run on this floor (None: some region holds it)."""
        cap = self.capacity()
        best = max(cap.values())
        return None if int(robots) <= best else (f"{robots} robots: the largest region of this floor holds {best} "
                                                 f"({', '.join(f'{k} {v}' for k, v in cap.items())})")

    def robot_bounds(self, positions: ArrayLike, assignment: Mapping[str, ArrayLike]) -> FloatArray:
        """``(N, 4)`` wall rectangles for the floor's barrier (floor frame, m): the robots of ``assignment[name]``
        (row indices of the floor's reading) get region ``name``'s bounds, every other robot the region its
        position ``(N, 2+)`` lies in, else the floor."""
        pos = np.asarray(positions, dtype=float).reshape(len(np.asarray(positions)), -1)
        out = np.tile(np.asarray(self.floor, dtype=float), (len(pos), 1))
        # a handful of regions, largest first: a robot gets the smallest region it lies in (nested layouts)
        for r in sorted(self.regions, key=lambda r: -r.bounds.width * r.bounds.height):
            out[r.bounds.contains(pos[:, :2])] = r.bounds
        for name, rows in assignment.items():
            out[np.asarray(rows, dtype=np.intp)] = self.region(name).bounds
        return out

    def to_dict(self) -> dict[str, Any]:
        return {"floor": list(self.floor), "regions": [r.to_dict() for r in self.regions],
                "capacity": self.capacity()}
