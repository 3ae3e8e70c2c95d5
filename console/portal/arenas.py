"""The arenas behind one portal: ``swarmdeck server --arena NAME=SPEC`` (repeatable), one :class:`ArenaSpec` each.

SPEC is comma-separated, its first item says where the robots are:

* ``sim`` — a simulated fleet in the server's process (``fast``: as fast as it computes);
* ``mqtt://HOST:PORT`` — GRITSBots over MQTT, driven by the server's process (physical);
* ``remote`` — an arena runner on another machine (``swarmdeck runner --portal URL --arena NAME --token T``) that
  pulls this arena's jobs over HTTP and pushes their results (:mod:`.remote`);

then ``robots=N`` (default 12), ``kind=physical|simulated`` (``remote`` only; ``sim`` is simulated, ``mqtt``
physical), ``fast``, ``slots=K`` (jobs the arena runs at once; default 1) and ``regions=LAYOUT`` (``sim`` only: the
floor divided into regions, one job per region at once — ``COLSxROWS``, ``auto:COLSxROWS`` (regions allocated per
job: :meth:`~swarmdeck.devices.fleet.regions.RegionLayout.guillotine`) or a TOML file with a ``[regions]`` table,
as ``swarmdeck regions`` takes; its robots are shared out between the regions; each region is one slot of the plan,
holding as many robots as are parked in it: :mod:`.region_runner`).

Examples: ``--arena floor=sim,robots=50,fast``, ``--arena big=sim,robots=24,regions=2x2``, ``--arena lab=mqtt://127.0.0.1:1883,robots=20``,
``--arena annex=remote,robots=12,kind=physical``. Pure Python (the thin CLI client may import it).
"""
from __future__ import annotations

import re
from dataclasses import dataclass

from swarmdeck.console.portal.errors import BadInput
from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds
from swarmdeck.devices.net.mqtt_config import parse_broker_url

#: what a job may ask for: physical robots, simulated ones, or either (the manifest's ``needs``)
NEEDS = ("either", "physical", "simulated")
KINDS = ("physical", "simulated")
#: an arena's name: what a manifest's ``arena``, URLs and the runner's ``--arena`` use
NAME_RE = re.compile(r"^[a-z][a-z0-9_-]{0,31}$")
#: a region layout written as a grid, COLSxROWS (``regions=2x2``)
GRID_RE = re.compile(r"^(\d+)x(\d+)$")
#: the arena of a portal started without ``--arena`` (the one arena of earlier versions)
DEFAULT_ARENA = "arena"


@dataclass(frozen=True)
class ArenaSpec:
    """One arena behind the portal (module docstring).

    Attributes:
        name: its name (:data:`NAME_RE`).
        kind: ``simulated`` or ``physical``.
        robots: robots its fleet has (the most a job placed on it may use).
        robots_via: ``mqtt://HOST:PORT`` of an in-process MQTT fleet; None otherwise.
        fast: simulated, in-process: jobs tick as fast as they compute.
        remote: its runner is another process that connects over HTTP (:mod:`.remote`).
        slots: jobs it runs at once (regions of one floor; 1: one job at a time).
        regions: the layout its floor is divided into (``COLSxROWS`` or a TOML file); None: one floor.
        slot_names: the regions' names, one per slot (filled in when the layout is loaded:
            :func:`~.region_runner.region_arena`); empty: slots are numbered.
        slot_robots: robots each slot (region) holds; empty: ``robots // slots``.
        slot_bounds: each slot's region as its job's script sees it (local bounds, m, centred on the region's
            origin; filled in with the layout: :func:`~.region_runner.region_arena`); empty: the whole floor
            (:data:`~swarmdeck.core.bounds.DEFAULT_BOUNDS`) for every slot. A job is verified against the region it
            will get (:meth:`job_bounds`) and planned only on slots of exactly those bounds.
        slot_conflicts: for each slot, the slots that cannot run a job at the same time (regions allocated per
            job: a region and the regions inside or around it, :meth:`~swarmdeck.devices.fleet.regions.RegionLayout.
            conflicts`); empty: none.
    """

    name: str
    kind: str = "simulated"
    robots: int = 12
    robots_via: str | None = None
    fast: bool = False
    remote: bool = False
    slots: int = 1
    regions: str | None = None
    slot_names: tuple[str, ...] = ()
    slot_robots: tuple[int, ...] = ()
    slot_bounds: tuple[Bounds, ...] = ()
    slot_conflicts: tuple[tuple[int, ...], ...] = ()

    def conflicts(self, slot: int) -> tuple[int, ...]:
        """The slots that cannot run a job while slot ``slot`` does (none unless its regions are nested)."""
        return tuple(self.slot_conflicts[slot]) if self.slot_conflicts else ()

    def slot_shape(self, slot: int) -> Bounds:
        """The arena a job on slot ``slot`` sees, m: its region's local bounds, else the whole floor."""
        return Bounds(*self.slot_bounds[slot]) if self.slot_bounds else DEFAULT_BOUNDS

    def job_bounds(self, robots: int) -> Bounds:
        """The arena a job of ``robots`` robots placed here sees, m — what it is verified against: the region of the
        smallest capacity that holds it (then the smallest area, then layout order), else the whole floor."""
        fitting = [k for k in range(self.slots) if self.slot_capacity(k) >= int(robots)] or list(range(self.slots))

        def key(k: int) -> tuple[int, float, int]:
            b = self.slot_shape(k)
            return self.slot_capacity(k), (b[1] - b[0]) * (b[3] - b[2]), k

        return self.slot_shape(min(fitting, key=key))

    def slot_capacity(self, slot: int) -> int:
        """Robots a job on slot ``slot`` may use (its region's; the whole fleet with one slot)."""
        if self.slot_robots:
            return int(self.slot_robots[slot])
        return self.robots if self.slots == 1 else self.robots // self.slots

    @property
    def largest(self) -> int:
        """The most robots one job on this arena may use (the largest slot's)."""
        return max(self.slot_capacity(k) for k in range(self.slots))

    def placed_name(self, slot: int | None) -> str:
        """What a job claimed on ``slot`` records as ``placed``: ``NAME/REGION`` on a divided floor, else ``NAME``."""
        if slot is None or not self.slot_names:
            return self.name
        return f"{self.name}/{self.slot_names[slot]}"

    def slot_of(self, placed: str | None) -> int | None:
        """The slot a job's ``placed`` names (None: no region named, or not one of this arena's)."""
        if placed is None or "/" not in placed:
            return None
        arena, _, region = placed.partition("/")
        if arena != self.name or region not in self.slot_names:
            return None
        return self.slot_names.index(region)

    def fits(self, robots: int, needs: str = "either", arena: str | None = None) -> bool:
        """Whether a job of ``robots`` robots that ``needs`` that kind (and asked for ``arena``) can run here."""
        return robots <= self.largest and needs in ("either", self.kind) and arena in (None, self.name)

    def describe(self) -> str:
        where = "remote runner" if self.remote else (f"MQTT robots via {self.robots_via}" if self.robots_via
                                                     else "simulated" + (", fast" if self.fast else ""))
        parts = f", regions {self.regions} ({self.slots} at once)" if self.regions else (
            f", {self.slots} slots" if self.slots > 1 else "")
        return f"{self.name}: {self.robots} {self.kind} robots ({where}{parts})"

    def to_dict(self) -> dict[str, object]:
        return {"name": self.name, "kind": self.kind, "robots": self.robots, "remote": self.remote,
                "slots": self.slots, "fast": self.fast, "regions": list(self.slot_names) or None,
                "slot_robots": [self.slot_capacity(k) for k in range(self.slots)]}


def parse_arena_spec(text: str) -> ArenaSpec:
    """``NAME=SPEC`` (module docstring) -> :class:`ArenaSpec`; :class:`ValueError` naming what is wrong."""
    name, sep, spec = str(text).partition("=")
    name = name.strip()
    if not sep or not spec.strip():
        raise ValueError(f"--arena {text!r}: write NAME=SPEC, e.g. floor=sim,robots=50")
    if not NAME_RE.match(name):
        raise ValueError(f"--arena {text!r}: the name {name!r} must be lower-case letters, digits, '-' or '_' "
                         "(at most 32, starting with a letter)")
    items = [s.strip() for s in spec.split(",")]
    where, options = items[0], items[1:]
    kind, robots_via, remote = "simulated", None, False
    if where == "sim":
        pass
    elif where.startswith("mqtt://"):
        parse_broker_url(where)  # ValueError naming the URL's problem
        kind, robots_via = "physical", where
    elif where == "remote":
        remote = True
    else:
        raise ValueError(f"--arena {name}: {where!r} is not sim, mqtt://HOST:PORT or remote")
    robots, fast, slots, kind_set, regions = 12, False, 1, None, None
    for opt in options:
        key, eq, value = opt.partition("=")
        try:
            if key == "robots" and eq:
                robots = int(value)
            elif key == "slots" and eq:
                slots = int(value)
            elif key == "kind" and eq:
                kind_set = value
            elif key == "fast" and not eq:
                fast = True
            elif key == "regions" and eq and value.strip():
                regions = value.strip()
            else:
                raise ValueError
        except ValueError:
            raise ValueError(f"--arena {name}: unknown or malformed option {opt!r} (robots=N, slots=K, "
                             "kind=physical|simulated, fast, regions=COLSxROWS|FILE.toml)") from None
    if robots < 1:
        raise ValueError(f"--arena {name}: robots must be >= 1, got {robots}")
    if slots < 1:
        raise ValueError(f"--arena {name}: slots must be >= 1, got {slots}")
    if kind_set is not None:
        if not remote:
            raise ValueError(f"--arena {name}: kind= is for a remote arena (sim is simulated, mqtt physical)")
        if kind_set not in KINDS:
            raise ValueError(f"--arena {name}: kind must be physical or simulated, got {kind_set!r}")
        kind = kind_set
    if fast and (robots_via is not None or remote):
        raise ValueError(f"--arena {name}: fast is for an in-process simulated arena")
    if regions is not None:
        if where != "sim":
            raise ValueError(f"--arena {name}: regions= divides an in-process simulated floor (sim) for now")
        if slots != 1:
            raise ValueError(f"--arena {name}: regions= sets the slots (one per region): leave out slots=")
        grid = GRID_RE.match(regions)
        if grid is not None:
            slots = int(grid.group(1)) * int(grid.group(2))
            if slots < 1:
                raise ValueError(f"--arena {name}: regions={regions} has no region")
    return ArenaSpec(name=name, kind=kind, robots=robots, robots_via=robots_via, fast=fast, remote=remote,
                     slots=slots, regions=regions)


def check_unique(specs: list[ArenaSpec]) -> None:
    """ValueError when two arenas share a name."""
    seen: set[str] = set()
    for s in specs:
        if s.name in seen:
            raise ValueError(f"--arena {s.name}: two arenas are named {s.name!r}")
        seen.add(s.name)


def check_request(arenas: tuple[ArenaSpec, ...], robots: int, needs: str, arena: str | None) -> None:
    """:class:`~.errors.BadInput` when no arena of this portal can ever run such a job (naming why)."""
    if needs not in NEEDS:
        raise BadInput(f"needs must be one of {', '.join(NEEDS)}, got {needs!r}", "needs")
    if arena is not None:
        named = [a for a in arenas if a.name == arena]
        if not named:
            raise BadInput(f"there is no arena {arena!r} (arenas: {', '.join(a.name for a in arenas)})", "arena")
        a = named[0]
        if needs not in ("either", a.kind):
            raise BadInput(f"arena {arena!r} is {a.kind}, the manifest needs {needs}", "needs")
        if robots > a.largest:
            held = f"(its floor divided into regions): the largest region holds {a.largest}" if a.slot_names \
                else f"has {a.robots}"
            raise BadInput(f"arena {arena!r} {held} robots, the manifest asks for {robots}", "robots")
        return
    kinds = [a for a in arenas if needs in ("either", a.kind)]
    if not kinds:
        raise BadInput(f"no arena here is {needs} (arenas: {', '.join(a.describe() for a in arenas)})", "needs")
    if not any(robots <= a.largest for a in kinds):
        raise BadInput(f"no {'' if needs == 'either' else needs + ' '}arena has {robots} robots for one job (the "
                       f"most one job may use is {max(a.largest for a in kinds)})", "robots")
