"""TUIO 1.1 (``/tuio/2Dcur|2Dobj|2Dblb``) and TUIO 2.0 (``/tuio2/frm ptr tok bnd alv``)
frame assembly (REFERENCE.md §6, notes/tuio.md §1–3).

TUIO 1.1: per *(sending host, source string, profile)* — not per port: one-shot
senders (oscsend) and reconnecting TCP tablets use a new port each time, as the
reference client keys by the source string — the ALIVE and SET messages are
buffered and committed at FSEQ, or at the end of the datagram for senders that
omit FSEQ (python-tuio sends one bundle for all profiles with a single FSEQ on
2Dcur). The late-frame rule of the reference clients applies per key: a frame
with ``fseq > 0`` is applied when ``fseq >= last`` or ``last - fseq > 100``
(sender restart: every contact of that profile is ended first); otherwise it is
late and dropped; ``fseq <= 0`` (−1 marks refresh bundles) is never late.
Equal FSEQ is normal (one large frame split into several bundles, each with the
full ALIVE). SETs for ids absent from the frame's ALIVE are ignored; an ALIVE
id with no SET yet is not a contact until its first SET.

The profiles of one *(host, source)* form one contact source: session ids are
shared across profiles, and a blob whose session id is a cursor's (TuioPad)
gives that cursor its size instead of being a second finger.

TUIO 2.0: frames open with ``/tuio2/frm f_id time dim source`` and close with
``/tuio2/alv``; state per *(host, frm source)*; a frame is late when
``0 < f_id < last`` and its FRM time is less than 1 s after the last frame's
(without usable times: the 1.1 restart gap). ``f_id`` 0 is never late. ``ptr``
≈ 2Dcur (negative pressure = hovering, not a contact), ``tok`` ≈ 2Dobj, ``bnd`` ≈
2Dblb (sharing a ptr/tok id gives it a size); the velocity tail is optional.
"""
from __future__ import annotations

import math
from datetime import datetime

from .frames import AREA, KIND, NAN, Problems, SourceFrame

RESTART_GAP = 100
MAX_GROUPS = 1024  # (sender, source) groups kept; beyond it the least recently used is forgotten
TUIO2_LATE_WINDOW = 1.0
_NUM = (int, float)

# profile -> (kind, accepted SET lengths incl. the "set" string)
_PROFILES_1 = {"2Dcur": ("cursor", (7, 9)), "2Dobj": ("object", (11,)), "2Dblb": ("blob", (13,))}
_ORDER_1 = ("2Dcur", "2Dobj", "2Dblb")
_ORDER_2 = ("ptr", "tok", "bnd")
_KIND_2 = {"ptr": "pointer", "tok": "token", "bnd": "bounds"}
_LEN_2 = {"ptr": (9, 14), "tok": (6, 11), "bnd": (7, 12)}
_IGNORED_2 = {"sym", "ctl", "dat", "ocg", "icg", "skg", "svg", "arg", "lia", "lla", "lta", "lit",
              "p3d", "t3d", "b3d", "r3d", "s3d", "coa", "ala", "cla", "chg"}
_NTP_EPOCH = datetime(1900, 1, 1)


class _Profile:
    __slots__ = ("last_fseq", "entities", "alive")

    def __init__(self) -> None:
        self.last_fseq: int | None = None
        self.entities: dict = {}
        self.alive: dict | None = None  # last committed ALIVE (ids may still lack a SET)


class _Group:
    """All profiles of one (peer, source) — one contact source."""

    __slots__ = ("name", "kind", "profiles", "last_fid", "last_ftime", "restart")

    def __init__(self, name: str, kind: str) -> None:
        self.name = name
        self.kind = kind
        self.profiles: dict[str, _Profile] = {}
        self.last_fid: int | None = None
        self.last_ftime: float | None = None
        self.restart = False


class _Buffer:
    __slots__ = ("alive", "sets", "fid", "ftime")

    def __init__(self) -> None:
        self.alive: list | None = None
        self.sets: dict = {}
        self.fid: int | None = None
        self.ftime: float | None = None


def _is_int(v) -> bool:
    return type(v) is int


def _timetag_seconds(v) -> float | None:
    """python-osc parses OSC ``t`` into ``(naive UTC datetime, 2**-32 fraction)``."""
    try:
        dt, frac = v
        return (dt - _NTP_EPOCH).total_seconds() + frac / 2**32 - 2208988800.0
    except Exception:
        return None


class TuioAssembler:
    """Stateful TUIO 1.1 + 2.0 frame assembly for one listener.

    Use: ``begin(sender)`` (the sending host, e.g. ``"udp://10.0.0.2"``), then
    ``message(address, params)`` for each message of the datagram in order, then
    ``end()`` → committed :class:`SourceFrame` s.
    Not thread-safe (the owning listener serialises datagrams).
    """

    def __init__(self, problems: Problems, restart_gap: int = RESTART_GAP, max_contacts: int = 64) -> None:
        self._problems = problems
        self._restart_gap = restart_gap
        self._max = int(max_contacts)
        self._groups: dict[tuple, _Group] = {}
        self._by_name: dict[str, tuple] = {}  # group name -> key (forget in O(1))
        self._peer = ""
        self._source = ""
        self._bufs: dict[tuple, _Buffer] = {}
        self._buf2: _Buffer | None = None
        self._src2 = ""
        self._dirty: dict[tuple, _Group] = {}

    # ------------------------------------------------------------------ datagram
    def begin(self, peer: str) -> None:
        """Start a datagram from ``peer``, the sending host (e.g. ``"udp://10.0.0.2"``)."""
        self._peer = peer
        self._source = ""
        self._bufs = {}
        self._buf2 = None
        self._src2 = ""
        self._dirty = {}

    def end(self) -> list[SourceFrame]:
        """Finish the datagram: commit FSEQ-less 1.1 buffers and an unclosed 2.0
        frame, return one frame per source that changed."""
        for (source, profile), buf in self._bufs.items():
            self._commit1(source, profile, buf, None)
        self._bufs = {}
        if self._buf2 is not None:
            self._commit2(self._src2, self._buf2, None)
            self._buf2 = None
        out = []
        for key, g in self._dirty.items():
            out.append(SourceFrame(g.name, g.kind, self._merge(g, key[1]), True, g.restart))
            g.restart = False
        self._dirty = {}
        return out

    def forget(self, name: str) -> None:
        """Drop the state of the source called ``name`` (after it was lost), so
        a sender that comes back with lower frame numbers is not taken as late
        (also when it was idle and forgotten)."""
        key = self._by_name.pop(name, None)
        if key is not None:
            self._groups.pop(key, None)

    def message(self, address: str, p: list) -> None:
        """Handle one ``/tuio/...`` or ``/tuio2/...`` message of the current datagram."""
        self.messages(((address, p),))

    def messages(self, msgs) -> list:
        """Handle the ``(address, params)`` messages of the current datagram in
        order; returns the ones that are neither ``/tuio/`` nor ``/tuio2/``."""
        rest = []
        bufs = self._bufs
        for address, p in msgs:
            if address == "/tuio/2Dcur" and len(p) == 7 and p[0] == "set":
                # fast path for the common 2Dcur SET (s x y X Y m), all floats, in range
                sid, x, y, vx, vy, m = p[1], p[2], p[3], p[4], p[5], p[6]
                if (type(sid) is int and type(x) is float and type(y) is float and type(vx) is float
                        and type(vy) is float and type(m) is float):
                    tot = x + y + vx + vy + m
                    if tot - tot == 0.0 and 0.0 <= x <= 1.0 and 0.0 <= y <= 1.0:
                        key = (self._source, "2Dcur")
                        buf = bufs.get(key)
                        if buf is None:
                            buf = bufs[key] = _Buffer()
                        buf.sets[sid] = (x, y, vx, vy, NAN, NAN, "cursor", None)
                        continue
                self._message1("2Dcur", p)
            elif address.startswith("/tuio/"):
                self._message1(address[6:], p)
            elif address.startswith("/tuio2/"):
                self._message2(address[7:], p)
            else:
                rest.append((address, p))
        return rest

    # ------------------------------------------------------------------ names
    def _group(self, version: int, source: str) -> _Group:
        key = (self._peer, version, source)
        groups = self._groups
        g = groups.pop(key, None)
        if g is not None:  # most recently used last: the oldest are evicted first
            groups[key] = g
            return g
        if len(groups) >= MAX_GROUPS:  # O(1): forget the least recently used group
            old_key = next(iter(groups))
            self._by_name.pop(groups.pop(old_key).name, None)
        if version == 1:
            name = f"{self._peer}/{source}" if source else f"{self._peer}/tuio"
        else:
            name = f"{self._peer}/tuio2/{source}" if source else f"{self._peer}/tuio2"
        g = _Group(name, "tuio" if version == 1 else "tuio2")
        groups[key] = g
        self._by_name[name] = key
        return g

    def _err(self, version: int, source: str, reason: str, detail: str) -> None:
        g = self._group(version, source)
        self._problems.error(g.name, g.kind, reason, detail)

    def _warn(self, version: int, source: str, reason: str) -> None:
        g = self._group(version, source)
        self._problems.warn(g.name, g.kind, reason)

    # ------------------------------------------------------------------ TUIO 1.1
    def _message1(self, profile: str, p: list) -> None:
        src = self._source
        spec = _PROFILES_1.get(profile)
        if spec is None:
            self._err(1, src, "unknown_profile", f"/tuio/{profile} is not a supported TUIO 1.1 profile (2Dcur, 2Dobj, 2Dblb)")
            return
        cmd = p[0] if p else None
        if cmd == "set":
            self._set1(profile, spec, p)
        elif cmd == "alive":
            ids = p[1:]
            if not all(map(_is_int, ids)):
                self._err(1, src, "bad_args", f"/tuio/{profile} alive expects int32 session ids, got {[type(v).__name__ for v in ids]}")
                return
            buf = self._buf1(profile)
            buf.alive = ids
        elif cmd == "fseq":
            if len(p) != 2 or not _is_int(p[1]):
                self._err(1, src, "bad_args", f"/tuio/{profile} fseq expects one int32, got {p[1:]!r}")
                return
            popped = self._bufs.pop((src, profile), None)
            buf = popped if popped is not None else _Buffer()
            self._commit1(src, profile, buf, p[1])
        elif cmd == "source":
            if len(p) != 2 or not isinstance(p[1], str):
                self._err(1, src, "bad_args", f"/tuio/{profile} source expects one string, got {p[1:]!r}")
                return
            self._source = p[1]
        else:
            self._err(1, src, "unknown_command", f"/tuio/{profile} command {cmd!r} is not source/alive/set/fseq")

    def _buf1(self, profile: str) -> _Buffer:
        key = (self._source, profile)
        buf = self._bufs.get(key)
        if buf is None:
            buf = self._bufs[key] = _Buffer()
        return buf

    def _set1(self, profile: str, spec: tuple, p: list) -> None:
        kind, lengths = spec
        n = len(p)
        if n not in lengths:
            self._err(1, self._source, "bad_args", f"/tuio/{profile} set expects {lengths[0] - 1} arguments after 'set', got {n - 1}")
            return
        sid = p[1]
        if type(sid) is not int:
            self._err(1, self._source, "bad_args", f"/tuio/{profile} set session id must be int32, got {type(sid).__name__}")
            return
        if profile == "2Dcur":
            vals = p[2:]
            cls = None
            x, y, vx, vy = p[2], p[3], p[4], p[5]
            area = p[7] * p[8] if n == 9 and type(p[7]) in _NUM and type(p[8]) in _NUM else NAN
        elif profile == "2Dobj":
            cls = p[2]
            if type(cls) is not int:
                self._err(1, self._source, "bad_args", f"/tuio/2Dobj set class id must be int32, got {type(cls).__name__}")
                return
            vals = p[3:]
            x, y, vx, vy = p[3], p[4], p[6], p[7]
            area = NAN
        else:
            cls = None
            vals = p[2:]
            x, y, vx, vy = p[2], p[3], p[8], p[9]
            area = p[7]
        for v in vals:
            if type(v) not in _NUM:
                self._err(1, self._source, "bad_args", f"/tuio/{profile} set expects numbers (f) after the ids, got {type(v).__name__} {v!r}")
                return
        if not math.isfinite(sum(vals)):
            self._err(1, self._source, "non_finite", f"/tuio/{profile} set for session {sid} has NaN or inf")
            return
        if not (0.0 <= x <= 1.0 and 0.0 <= y <= 1.0):
            self._warn(1, self._source, "out_of_range")
            x = min(max(x, 0.0), 1.0)
            y = min(max(y, 0.0), 1.0)
        self._buf1(profile).sets[sid] = (float(x), float(y), float(vx), float(vy), float(area), NAN, kind, cls)

    def _commit1(self, source: str, profile: str, buf: _Buffer, fseq: int | None) -> None:
        g = self._group(1, source)
        st = g.profiles.get(profile)
        if st is None:
            st = g.profiles[profile] = _Profile()
        if fseq is not None and fseq > 0:
            last = st.last_fseq
            if last is not None and fseq < last:
                if last - fseq > self._restart_gap:
                    self._problems.warn(g.name, g.kind, "restart")
                    for other in g.profiles.values():
                        other.entities = {}
                        other.alive = None
                        other.last_fseq = None
                    g.restart = True
                else:
                    self._problems.warn(g.name, g.kind, "late")
                    return
            st.last_fseq = fseq
        self._apply(g, st, buf)

    def _apply(self, g: _Group, st: _Profile, buf: _Buffer) -> None:
        old = st.entities
        sets = buf.sets
        if buf.alive is not None:
            alive = st.alive = dict.fromkeys(buf.alive)  # ordered, like the ALIVE list
        elif st.alive is not None:  # frame without ALIVE: the last ALIVE still holds
            alive = st.alive
        else:  # a sender that never sent ALIVE: take its SETs as they come
            alive = {**dict.fromkeys(old), **dict.fromkeys(sets)}
        new = {}
        for sid in alive:
            e = sets.get(sid)
            if e is None:
                e = old.get(sid)
            if e is not None:
                new[sid] = e
        if sets and any(sid not in alive for sid in sets):
            self._problems.warn(g.name, g.kind, "set_not_alive")
        st.entities = self._cap(g, new, old)
        self._dirty[(self._peer, g.kind, g.name)] = g

    def _cap(self, g: _Group, new: dict, old: dict) -> dict:
        """At most ``max_contacts`` entities per profile: those already held first,
        then new ones in ALIVE order; the rest are dropped and counted."""
        if len(new) <= self._max:
            return new
        keep = [sid for sid in new if sid in old][:self._max]
        room = self._max - len(keep)
        keep_set = set(keep)
        keep += [sid for sid in new if sid not in keep_set][:room]
        dropped = len(new) - len(keep)
        self._problems.error(g.name, g.kind, "too_many_contacts",
                             f"{dropped} contact(s) dropped: the limit of {self._max} contacts per source "
                             f"(max_contacts_per_source) was reached", dropped)
        keep_set = set(keep)
        return {sid: e for sid, e in new.items() if sid in keep_set}

    def _merge(self, g: _Group, kind: str) -> dict:
        """One entity per session id over the profiles of ``g``. A blob/bounds with
        the id of a cursor/object/pointer/token sizes it; a cursor and an object (or
        a pointer and a token) with one id are a sender bug (session ids are unique
        per source): the first profile's entity stays, the clash is counted."""
        order = _ORDER_1 if kind == "tuio" else _ORDER_2
        merged: dict = {}
        first: dict = {}  # sid -> profile that made the contact
        hovering: set = set()
        for prof in order:
            st = g.profiles.get(prof)
            if st is None:
                continue
            for sid, e in st.entities.items():
                if e[KIND] == "pointer" and e[5] < 0:  # hovering pointer: not a contact
                    hovering.add(sid)
                    continue
                if sid in hovering:
                    continue
                m = merged.get(sid)
                if m is None:
                    merged[sid] = e
                    first[sid] = prof
                elif e[KIND] in ("blob", "bounds"):
                    if e[AREA] == e[AREA]:
                        merged[sid] = m[:AREA] + (e[AREA],) + m[AREA + 1:]
                else:
                    self._problems.error(g.name, g.kind, "id_clash",
                                         f"{prof} session {sid} is also a {first[sid]} session of this source; "
                                         f"the {e[KIND]} is dropped (TUIO session ids are unique per source)")
        return merged

    # ------------------------------------------------------------------ TUIO 2.0
    def _message2(self, kind: str, p: list) -> None:
        if kind == "frm":
            if self._buf2 is not None:  # previous frame not closed by alv
                self._commit2(self._src2, self._buf2, None)
            if not p or type(p[0]) is not int:
                self._err(2, "", "bad_args", f"/tuio2/frm expects 'f_id time dim source' (i t i s), got {p!r}")
                self._buf2 = None
                return
            src = p[3] if len(p) >= 4 and isinstance(p[3], str) else ""
            buf = _Buffer()
            buf.fid = p[0]
            buf.ftime = _timetag_seconds(p[1]) if len(p) >= 2 else None
            self._buf2 = buf
            self._src2 = src
        elif kind in _LEN_2:
            self._component2(kind, p)
        elif kind == "alv":
            if not all(map(_is_int, p)):
                self._err(2, self._src2, "bad_args", f"/tuio2/alv expects int32 session ids, got {[type(v).__name__ for v in p]}")
                return
            buf = self._buf2 or _Buffer()
            buf.alive = p
            self._commit2(self._src2, buf, buf.fid)
            self._buf2 = None
        elif kind in _IGNORED_2:
            self._warn(2, self._src2, f"ignored_{kind}")
        else:
            self._err(2, self._src2, "unknown_profile", f"/tuio2/{kind} is not a TUIO 2.0 message this client knows")

    def _component2(self, kind: str, p: list) -> None:
        n = len(p)
        if n not in _LEN_2[kind]:
            self._err(2, self._src2, "bad_args", f"/tuio2/{kind} expects {_LEN_2[kind][0]} or {_LEN_2[kind][1]} arguments, got {n}")
            return
        if kind == "bnd":
            ints, vals = p[:1], p[1:]
        else:
            ints, vals = p[:3], p[3:]
        if not all(map(_is_int, ints)):
            self._err(2, self._src2, "bad_args", f"/tuio2/{kind} ids must be int32, got {[type(v).__name__ for v in ints]}")
            return
        for v in vals:
            if type(v) not in _NUM:
                self._err(2, self._src2, "bad_args", f"/tuio2/{kind} expects numbers (f) after the ids, got {type(v).__name__} {v!r}")
                return
        if not math.isfinite(sum(vals)):
            self._err(2, self._src2, "non_finite", f"/tuio2/{kind} for session {p[0]} has NaN or inf")
            return
        sid = p[0]
        if kind == "ptr":
            x, y = p[3], p[4]
            vel = (p[9], p[10]) if n == 14 else (NAN, NAN)
            area, press, cls = math.pi * float(p[7]) ** 2, float(p[8]), p[2]
        elif kind == "tok":
            x, y = p[3], p[4]
            vel = (p[6], p[7]) if n == 11 else (NAN, NAN)
            area, press, cls = NAN, NAN, p[2]
        else:
            x, y = p[1], p[2]
            vel = (p[7], p[8]) if n == 12 else (NAN, NAN)
            area, press, cls = float(p[6]), NAN, None
        if not (0.0 <= x <= 1.0 and 0.0 <= y <= 1.0):
            self._warn(2, self._src2, "out_of_range")
            x = min(max(x, 0.0), 1.0)
            y = min(max(y, 0.0), 1.0)
        if self._buf2 is None:
            self._buf2 = _Buffer()
            self._src2 = ""
        self._buf2.sets[(kind, sid)] = (float(x), float(y), float(vel[0]), float(vel[1]), area, press, _KIND_2[kind], cls)

    def _commit2(self, source: str, buf: _Buffer, fid: int | None) -> None:
        g = self._group(2, source)
        if fid is not None and fid != 0:
            last = g.last_fid
            if last is not None and fid < last:
                t, lt = buf.ftime, g.last_ftime
                if t is not None and lt is not None:
                    late = t - lt < TUIO2_LATE_WINDOW
                else:
                    late = last - fid <= self._restart_gap
                if late:
                    self._problems.warn(g.name, g.kind, "late")
                    return
                self._problems.warn(g.name, g.kind, "restart")
                for st in g.profiles.values():
                    st.entities = {}
                g.restart = True
            g.last_fid = fid
            g.last_ftime = buf.ftime
        for comp in _ORDER_2:
            found = g.profiles.get(comp)
            if found is None:
                found = g.profiles[comp] = _Profile()
            st = found
            sub = _Buffer()
            sub.alive = buf.alive
            sub.sets = {sid: e for (k, sid), e in buf.sets.items() if k == comp}
            if buf.alive is None and not sub.sets:
                continue
            self._apply2(g, st, sub)

    def _apply2(self, g: _Group, st: _Profile, buf: _Buffer) -> None:
        # The alv list covers every component type; an id alive without a message
        # of this type in the frame keeps its previous state (or has none).
        old = st.entities
        if buf.alive is None:  # frame not closed by alv (non-conforming): update only
            new = dict(old)
            new.update(buf.sets)
        else:
            new = {}
            for sid in buf.alive:
                e = buf.sets.get(sid)
                if e is None:
                    e = old.get(sid)
                if e is not None:
                    new[sid] = e
        st.entities = self._cap(g, new, old)
        self._dirty[(self._peer, g.kind, g.name)] = g
