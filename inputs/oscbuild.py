"""Encode OSC messages and bundles with *explicit* type tags, and TUIO 1.1/2.0
frames (for tests, benchmarks and ``swarmdeck inputs send``-style tools).

python-osc's ``OscMessageBuilder`` infers types (a Python int becomes ``i``,
which strict receivers reject where ``f`` is expected) and cannot encode ``t``
(needed by ``/tuio2/frm``); this encoder takes the type tag string verbatim.
Supported tags: ``i h f d s S b t T F N`` (``t`` takes Unix seconds or
``None`` = immediately).
"""
from __future__ import annotations

import struct
from collections.abc import Sequence
from typing import Any

NTP_DELTA = 2208988800.0  # seconds from 1900-01-01 to 1970-01-01

_SET_TAGS = {"2Dcur": "si" + "f" * 5, "2Dobj": "sii" + "f" * 8, "2Dblb": "si" + "f" * 11}


def _pad(b: bytes) -> bytes:
    return b + b"\x00" * (4 - len(b) % 4)


def _str(s: str) -> bytes:
    return _pad(s.encode("utf-8"))


def timetag(unix_seconds: float | None) -> bytes:
    """8-byte OSC timetag; ``None`` is the special value *immediately*."""
    if unix_seconds is None:
        return b"\x00\x00\x00\x00\x00\x00\x00\x01"
    ntp = unix_seconds + NTP_DELTA
    sec = int(ntp)
    frac = int((ntp - sec) * 2**32) & 0xFFFFFFFF
    return struct.pack(">II", sec & 0xFFFFFFFF, frac)


def message(address: str, tags: str, *args: Any) -> bytes:
    """One OSC message; ``tags`` without the leading comma, one letter per argument
    except ``T F N`` (no argument)."""
    out = [_str(address), _str("," + tags)]
    it = iter(args)
    for tag in tags:
        if tag in "TFN":
            continue
        v = next(it)
        if tag == "i":
            out.append(struct.pack(">i", v))
        elif tag == "h":
            out.append(struct.pack(">q", v))
        elif tag == "f":
            out.append(struct.pack(">f", v))
        elif tag == "d":
            out.append(struct.pack(">d", v))
        elif tag in "sS":
            out.append(_str(v))
        elif tag == "b":
            out.append(struct.pack(">i", len(v)) + bytes(v) + b"\x00" * (-len(v) % 4))
        elif tag == "t":
            out.append(timetag(v))
        else:
            raise ValueError(f"unsupported type tag {tag!r}")
    rest = list(it)
    if rest:
        raise ValueError(f"{len(rest)} argument(s) left over for type tags {tags!r}")
    return b"".join(out)


def bundle(*elements: bytes, at: float | None = None) -> bytes:
    """An OSC bundle of encoded messages/bundles; ``at`` = Unix-seconds timetag
    (``None`` = immediately)."""
    parts = [b"#bundle\x00", timetag(at)]
    for e in elements:
        parts.append(struct.pack(">i", len(e)))
        parts.append(e)
    return b"".join(parts)


def tuio_messages(profile: str, alive: Sequence[int], sets: Sequence[Sequence[float]] = (),
                  fseq: int | None = None, source: str | None = None) -> list[bytes]:
    """``[source] alive set* [fseq]`` messages of one TUIO 1.1 profile. Each
    entry of ``sets`` is the argument list after ``"set"``: 2Dcur ``s x y X Y m``,
    2Dobj ``s i x y a X Y A m r``, 2Dblb ``s x y a w h f X Y A m r``."""
    addr = f"/tuio/{profile}"
    msgs = []
    if source is not None:
        msgs.append(message(addr, "ss", "source", source))
    msgs.append(message(addr, "s" + "i" * len(alive), "alive", *alive))
    tags = _SET_TAGS[profile]
    for s in sets:
        msgs.append(message(addr, tags, "set", *s))
    if fseq is not None:
        msgs.append(message(addr, "si", "fseq", fseq))
    return msgs


def tuio_bundle(profile: str, alive: Sequence[int], sets: Sequence[Sequence[float]] = (),
                fseq: int | None = None, source: str | None = None, at: float | None = None) -> bytes:
    """One TUIO 1.1 bundle (see :func:`tuio_messages`)."""
    return bundle(*tuio_messages(profile, alive, sets, fseq, source), at=at)


def cursor_sets(points: Sequence[tuple[int, float, float]], vel: tuple[float, float] = (0.0, 0.0)) -> list[tuple]:
    """2Dcur SET argument tuples ``(s, x, y, X, Y, m)`` from ``(s, x, y)`` points."""
    return [(s, x, y, vel[0], vel[1], 0.0) for s, x, y in points]


def tuio2_frame(fid: int, source: str, components: Sequence[tuple[str, str, Sequence[object]]],
                alive: Sequence[int], time: float | None = None, dim: int = 0x028001E0) -> bytes:
    """A TUIO 2.0 bundle: ``/tuio2/frm f_id time dim source``, the component
    messages ``(kind, tags, args)`` (e.g. ``("ptr", "iiifffffff"..., [...])``), ``/tuio2/alv``."""
    msgs = [message("/tuio2/frm", "itis", fid, time, dim, source)]
    for kind, tags, args in components:
        msgs.append(message(f"/tuio2/{kind}", tags, *args))
    msgs.append(message("/tuio2/alv", "i" * len(alive), *alive))
    return bundle(*msgs)
