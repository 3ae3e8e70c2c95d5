"""Generic OSC point streams: gesture bridges that send plain OSC (no ALIVE).

A :class:`PointStreamConfig` says which addresses carry a point, which arguments
hold its x and y, how raw units map onto the normalised surface (origin top-left,
y down, like TUIO) and which address fields or arguments identify the point.
Points have no ALIVE list: each one is removed ("up") when it has not been
updated for ``presence_timeout`` seconds.

Presets (REFERENCE.md §6, notes/tuio.md §5.2; Leap frame: mm, y up, z towards
the user, so the floor plane is Leap x (right) and z (down on the surface)):

* ``manososc``: ``/finger<h>-<f>  s name, i hand, i finger, f x, f y, f z`` on
  port 7110; one point per (hand, finger).
* ``leap-osc``: ``/leap/<h>/<f>/pos  f x, f y, f z`` (mm); one point per (h, f).
* ``ultraleap-osc-sender``: ``/leap/left`` and ``/leap/right`` palm ``x y z``
  (mm) on port 5000; one point per hand.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from types import MappingProxyType

from swarmdeck.core.config import check_keys, field_names

from .frames import NAN, Problems, SourceFrame

_NUM = (int, float)
MAX_IDS_PER_STREAM = 1024


@dataclass(frozen=True)
class PointStreamConfig:
    """One kind of point message.

    Attributes:
        name: stream name; the contact source is ``"<peer>/<name>"``.
        address: address template; ``{field}`` matches one path piece (no ``/``)
            and names it, ``*`` matches any run of non-``/`` characters,
            e.g. ``"/leap/{hand}/{finger}/pos"``.
        x_arg, y_arg: argument indices of the two coordinates.
        id_fields: address field names (str) and/or argument indices (int) whose
            values identify a point; ``()`` = one point per stream.
        scale: raw value × scale = value in the units of ``x_range``/``y_range``
            (e.g. 0.001 turns mm into m).
        x_range, y_range: scaled values mapped linearly onto surface 0..1
            (``y_range`` onto v, which points *down*; give ``(hi, lo)`` to flip).
        flip_x, flip_y: mirror the normalised axis (u → 1 − u, v → 1 − v).
        presence_timeout: s without an update after which the point is "up".
        port: the preset's default port (used by ``ListenerConfig`` presets).
    """

    name: str
    address: str
    x_arg: int = 0
    y_arg: int = 1
    id_fields: tuple = ()
    scale: float = 1.0
    x_range: tuple[float, float] = (0.0, 1.0)
    y_range: tuple[float, float] = (0.0, 1.0)
    flip_x: bool = False
    flip_y: bool = False
    presence_timeout: float = 0.25
    port: int | None = None
    _regex: re.Pattern = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not self.address.startswith("/"):
            raise ValueError(f"point stream {self.name!r}: address template must start with '/', got {self.address!r}")
        if self.x_range[0] == self.x_range[1] or self.y_range[0] == self.y_range[1]:
            raise ValueError(f"point stream {self.name!r}: x_range and y_range must have distinct ends")
        if not (self.presence_timeout > 0):
            raise ValueError(f"point stream {self.name!r}: presence_timeout must be > 0 s, got {self.presence_timeout}")
        if self.x_arg < 0 or self.y_arg < 0:
            raise ValueError(f"point stream {self.name!r}: x_arg and y_arg are argument indices (>= 0)")
        parts = re.split(r"(\{[A-Za-z_][A-Za-z0-9_]*\}|\*)", self.address)
        rx = []
        names = set()
        for part in parts:
            if part == "*":
                rx.append(r"[^/]*")
            elif part.startswith("{") and part.endswith("}"):
                names.add(part[1:-1])
                rx.append(f"(?P<{part[1:-1]}>[^/]+?)")
            else:
                rx.append(re.escape(part))
        for f in self.id_fields:
            if isinstance(f, str) and f not in names:
                raise ValueError(f"point stream {self.name!r}: id field {f!r} is not a {{field}} of {self.address!r}")
            if not isinstance(f, (str, int)) or isinstance(f, bool):
                raise ValueError(f"point stream {self.name!r}: id fields are names or argument indices, got {f!r}")
        object.__setattr__(self, "_regex", re.compile("".join(rx) + r"\Z"))

    def match(self, address: str) -> dict | None:
        """Field values if ``address`` matches the template, else ``None``."""
        m = self._regex.match(address)
        return None if m is None else m.groupdict()

    @classmethod
    def from_dict(cls, d: dict) -> PointStreamConfig:
        """Build from a config mapping; unknown keys are an error."""
        kw = check_keys(d, field_names(cls), "point stream", error=ValueError)
        for k in ("x_range", "y_range"):
            if k in kw:
                kw[k] = tuple(float(v) for v in kw[k])
        if "id_fields" in kw:
            kw["id_fields"] = tuple(kw["id_fields"])
        return cls(**kw)


_LEAP_X = (-0.2, 0.2)   # m, Leap x (right) over the interaction box
_LEAP_Z = (-0.15, 0.15)  # m, Leap z (towards the user) → surface v (down)

#: Read-only preset name → point streams.
PRESETS: MappingProxyType = MappingProxyType({
    "manososc": (PointStreamConfig(
        name="manososc", address="/finger{hand}-{finger}", x_arg=3, y_arg=5, id_fields=(1, 2),
        scale=0.001, x_range=_LEAP_X, y_range=_LEAP_Z, port=7110),),
    "leap-osc": (PointStreamConfig(
        name="leap-osc", address="/leap/{hand}/{finger}/pos", x_arg=0, y_arg=2,
        id_fields=("hand", "finger"), scale=0.001, x_range=_LEAP_X, y_range=_LEAP_Z),),
    "ultraleap-osc-sender": (PointStreamConfig(
        name="ultraleap", address="/leap/{side}", x_arg=0, y_arg=2, id_fields=("side",),
        scale=0.001, x_range=_LEAP_X, y_range=_LEAP_Z, port=5000),),
})


class PointStreamDecoder:
    """Turns matching OSC messages into partial :class:`SourceFrame` s."""

    def __init__(self, streams: tuple[PointStreamConfig, ...], problems: Problems) -> None:
        self._streams = tuple(streams)
        self._problems = problems
        self._ids: dict[str, dict[tuple, int]] = {}
        self._frames: dict[str, SourceFrame] = {}
        self._peer = ""

    @property
    def streams(self) -> tuple[PointStreamConfig, ...]:
        """The configured streams."""
        return self._streams

    def begin(self, peer: str) -> None:
        """Start a datagram from ``peer``."""
        self._peer = peer
        self._frames = {}

    def end(self) -> list[SourceFrame]:
        """The partial frames of this datagram, one per stream that had points."""
        out = list(self._frames.values())
        self._frames = {}
        return out

    def forget(self, name: str) -> None:
        """Forget the id assignments of the source ``name`` (after it was lost)."""
        self._ids.pop(name, None)

    def message(self, address: str, params: list) -> bool:
        """Handle a message; ``False`` if no stream's address template matches."""
        for s in self._streams:
            fields = s.match(address)
            if fields is not None:
                self._point(s, fields, address, params)
                return True
        return False

    def _point(self, s: PointStreamConfig, fields: dict, address: str, p: list) -> None:
        name = f"{self._peer}/{s.name}"
        need = max(s.x_arg, s.y_arg, *[f for f in s.id_fields if isinstance(f, int)], 0) + 1
        if len(p) < need:
            self._problems.error(name, "points", "bad_args", f"{address} needs at least {need} arguments, got {len(p)}")
            return
        x, y = p[s.x_arg], p[s.y_arg]
        if type(x) not in _NUM or type(y) not in _NUM:
            self._problems.error(name, "points", "bad_args", f"{address} arguments {s.x_arg} and {s.y_arg} must be numbers, got {type(x).__name__}, {type(y).__name__}")
            return
        if not (math.isfinite(x) and math.isfinite(y)):
            self._problems.error(name, "points", "non_finite", f"{address} has NaN or inf coordinates")
            return
        u = (x * s.scale - s.x_range[0]) / (s.x_range[1] - s.x_range[0])
        v = (y * s.scale - s.y_range[0]) / (s.y_range[1] - s.y_range[0])
        if s.flip_x:
            u = 1.0 - u
        if s.flip_y:
            v = 1.0 - v
        if not (0.0 <= u <= 1.0 and 0.0 <= v <= 1.0):
            self._problems.warn(name, "points", "out_of_range")
            u = min(max(u, 0.0), 1.0)
            v = min(max(v, 0.0), 1.0)
        key = tuple(fields[f] if isinstance(f, str) else p[f] for f in s.id_fields)
        ids = self._ids.get(name)
        if ids is None:
            if len(self._ids) >= MAX_IDS_PER_STREAM:  # many ephemeral peers: forget the oldest
                del self._ids[next(iter(self._ids))]
            ids = self._ids[name] = {}
        pid = ids.get(key)
        if pid is None:
            if len(ids) >= MAX_IDS_PER_STREAM:
                self._problems.error(name, "points", "too_many_ids", f"more than {MAX_IDS_PER_STREAM} distinct point ids; {key!r} ignored")
                return
            pid = ids[key] = len(ids)
        frame = self._frames.get(name)
        if frame is None:
            frame = self._frames[name] = SourceFrame(name, "points", {}, complete=False,
                                                     presence_timeout=s.presence_timeout)
        frame.points[pid] = (float(u), float(v), NAN, NAN, NAN, NAN, "point", None)
