"""Robot transport over MQTT in the GRITSBot X wire format (REFERENCE.md §9).

Commands go out on ``matlab_api/<id>``; robot status comes in on
``<id>/status`` and tracker-style poses on
``overhead_tracker/all_robot_pose_data``. Everything that arrives is checked:
malformed JSON, unknown ids, one robot id reported by two nodes, and messages
older than what was already seen are dropped with a clear message and counted
(:meth:`MqttTransport.status`), never raised. While the broker is unreachable
``send`` delivers nothing and says so; the robots brake by their own 500 ms
timeout, and the link reconnects with back-off in the background.
"""
from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.devices.net.link import MqttLink
from swarmdeck.devices.net.mqtt_config import MqttConfig
from swarmdeck.devices.net.transport import (
    LINK_MISSING,
    LINK_OK,
    LINK_STALE,
    LINK_UNKNOWN,
    Counters,
    PoseSample,
    RobotStatusTable,
    TransportStatus,
    check_command,
)
from swarmdeck.devices.net.wire import WireError, decode_poses, decode_status, encode_commands

LINK_DUPLICATE = "duplicate"  # two nodes claim this id: commands reach both, so it is not controlled


@dataclass(frozen=True)
class LinkTimeouts:
    """When a robot counts as stale or missing (console side).

    Attributes:
        stale_after: pose older than this → ``stale`` (REFERENCE.md §9 monitor: 0.1 s).
        missing_after: neither pose nor status for this long → ``missing`` (status comes every 1 s).
        duplicate_hold: after two nodes claimed one id, treat it as duplicated for this long, s.
    """

    stale_after: float = 0.1
    missing_after: float = 2.5
    duplicate_hold: float = 5.0


class _Table:
    """Per-robot receive state, grown as robots appear (guarded by the transport's lock)."""

    def __init__(self) -> None:
        self.rows: dict[int, int] = {}
        self.ids = np.empty(0, dtype=np.intp)
        self.pose = np.empty((0, 3))
        self.pose_t = np.empty(0)  # receive time
        self.pose_sender_t = np.empty(0)  # sender's stamp (NaN unknown)
        self.batt = np.empty(0)
        self.charging = np.empty(0, dtype=bool)
        self.status_t = np.empty(0)
        self.cmd_age = np.empty(0)
        self.seq = np.empty(0, dtype=np.int64)
        self.node: list[str | None] = []
        self.duplicate_t = np.empty(0)

    def row(self, rid: int) -> int:
        r = self.rows.get(rid)
        if r is not None:
            return r
        r = len(self.ids)
        self.rows[rid] = r
        self.ids = np.append(self.ids, rid)
        self.pose = np.vstack((self.pose, np.full((1, 3), np.nan)))
        self.pose_t = np.append(self.pose_t, -np.inf)
        self.pose_sender_t = np.append(self.pose_sender_t, np.nan)
        self.batt = np.append(self.batt, np.nan)
        self.charging = np.append(self.charging, False)
        self.status_t = np.append(self.status_t, -np.inf)
        self.cmd_age = np.append(self.cmd_age, np.nan)
        self.seq = np.append(self.seq, -1)
        self.node.append(None)
        self.duplicate_t = np.append(self.duplicate_t, -np.inf)
        return r


class MqttTransport:
    """Drive GRITSBots (real, or ``swarmdeck robots``) through an MQTT broker.

    Args:
        config: broker, topic prefix, QoS, protocol, TLS, credentials.
        ids: the robot ids this console controls; messages about other ids are
            counted as ``unknown_id`` and ignored. None: every id heard of is accepted.
        timeouts: stale/missing thresholds.
        clock: monotonic clock (receive stamps).

    Use :meth:`start` (or a ``with`` block) to connect; the constructor does no I/O.
    """

    def __init__(
        self,
        config: MqttConfig,
        ids: ArrayLike | None = None,
        *,
        timeouts: LinkTimeouts = LinkTimeouts(),
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.config = config
        self.timeouts = timeouts
        self.clock = clock
        self.counters = Counters()
        self._lock = threading.Lock()
        self._t = _Table()
        self.expected: frozenset[int] | None = None
        if ids is not None:
            arr = np.asarray(ids, dtype=np.intp).reshape(-1)
            if np.any(arr < 0) or len(np.unique(arr)) != len(arr):
                raise ValueError(f"ids must be distinct non-negative integers, got {arr.tolist()}")
            self.expected = frozenset(int(i) for i in arr)
            for i in sorted(self.expected):  # once, at construction
                self._t.row(i)
        self._expected_arr = None if self.expected is None else np.array(sorted(self.expected), dtype=np.intp)
        self._topic_cache: dict[int, str] = {}
        self.link = MqttLink(
            config,
            subscriptions=[config.pose_topic, config.status_wildcard],
            on_message=self._on_message,
            counters=self.counters,
            name="console",
            clock=clock,
        )

    # ---------------------------------------------------------------- lifetime
    def start(self) -> MqttTransport:
        self.link.start()
        return self

    def __enter__(self) -> MqttTransport:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Command every known robot to zero once (best effort), then disconnect."""
        with self._lock:
            ids = self._t.ids.copy()
        if len(ids) and self.link.connected:
            self.send(ids, np.zeros(len(ids)), np.zeros(len(ids)))
        self.link.close()

    # ---------------------------------------------------------------- commands
    def _topics(self, ids: NDArray[np.intp]) -> list[str]:
        cache = self._topic_cache
        out = []
        for i in ids.tolist():  # topic strings are cached: one dict lookup per robot
            t = cache.get(i)
            if t is None:
                t = cache[i] = self.config.command_topic(i)
            out.append(t)
        return out

    def send(self, ids: ArrayLike, v: ArrayLike, w: ArrayLike, leds: ArrayLike | None = None) -> bool:
        """Publish one command per robot (see :class:`~swarmdeck.devices.net.transport.RobotTransport`).

        Returns False when anything was not delivered (not connected, bad input).
        """
        cmd = check_command(ids, v, w, leds)
        ok = True
        for p in cmd.problems:
            self.counters.add("bad_command", p)
            ok = False
        sel = cmd.ids
        v_out, w_out, led_out = cmd.v, cmd.w, cmd.leds
        if self._expected_arr is not None and len(sel):
            known = np.isin(sel, self._expected_arr)
            if not known.all():
                self.counters.add("unknown_id", f"command for unknown robot id(s) {sel[~known].tolist()} not sent "
                                  f"(this console controls {sorted(self.expected or ())})")
                sel, v_out, w_out = sel[known], v_out[known], w_out[known]
                led_out = None if led_out is None else led_out[known]
                ok = False
        if not len(sel):
            return ok
        if not self.link.connected:
            self.counters.add("undeliverable", f"{len(sel)} command(s) not delivered: {self.link.state}", n=len(sel))
            return False
        sent = self.link.publish_many(self._topics(sel), encode_commands(v_out, w_out, led_out), expire=True)
        if sent < len(sel):
            self.counters.add("undeliverable", f"{len(sel) - sent} command(s) not delivered: {self.link.state}",
                              n=len(sel) - sent)
            return False
        self.counters.add("commands_sent", n=sent)
        return ok

    # ---------------------------------------------------------------- receiving
    def _on_message(self, topic: str, payload: bytes, t: float) -> None:
        if topic == self.config.pose_topic:
            self._on_poses(payload, t)
            return
        rid = self.config.robot_id_of_status_topic(topic)
        if rid is None:
            self.counters.add("unknown_topic", f"ignored message on unexpected topic {topic!r}")
            return
        self._on_status(rid, payload, t)

    def _known(self, rid: int) -> bool:
        if self.expected is None or rid in self.expected:
            return True
        self.counters.add("unknown_id", f"message about unknown robot id {rid} ignored "
                          f"(this console controls {sorted(self.expected or ())})")
        return False

    def _on_status(self, rid: int, payload: bytes, t: float) -> None:
        try:
            st = decode_status(payload)
        except WireError as exc:
            self.counters.add("malformed_status", f"robot {rid}: {exc}")
            return
        if not self._known(rid):
            return
        with self._lock:
            tab = self._t
            r = tab.row(rid)
            prev_node = tab.node[r]
            if st.node is not None and prev_node is not None and st.node != prev_node:
                if t - tab.status_t[r] < self.timeouts.missing_after:
                    tab.duplicate_t[r] = t
                    msg = (f"duplicate robot id {rid}: reported by two nodes ({prev_node!r} and {st.node!r}); "
                           "robot excluded from control")
                    self.counters.add("duplicate_id", msg)
                    tab.node[r] = st.node
                    return
            elif st.seq is not None and tab.seq[r] >= 0 and st.seq < tab.seq[r] and t - tab.status_t[r] < self.timeouts.missing_after:
                self.counters.add("out_of_order", f"robot {rid}: status seq {st.seq} after {tab.seq[r]}: dropped")
                return
            tab.node[r] = st.node
            tab.seq[r] = -1 if st.seq is None else st.seq
            tab.batt[r] = st.batt_volt
            tab.charging[r] = st.charge_status
            tab.cmd_age[r] = np.nan if st.cmd_age is None else st.cmd_age
            tab.status_t[r] = t
        self.counters.add("status_received")

    def _on_poses(self, payload: bytes, t: float) -> None:
        try:
            msg = decode_poses(payload)
        except WireError as exc:
            self.counters.add("malformed_poses", str(exc))
            return
        for p in msg.problems:
            self.counters.add("bad_pose_rows", p)
        ids = msg.ids
        keep = np.ones(len(ids), dtype=bool)
        if self._expected_arr is not None:
            keep = np.isin(ids, self._expected_arr)
            if not keep.all():
                self.counters.add("unknown_id", f"poses of unknown robot id(s) {ids[~keep].tolist()} ignored",
                                  n=int((~keep).sum()))
        with self._lock:
            tab = self._t
            rows = np.fromiter((tab.row(int(i)) for i in ids[keep].tolist()), np.intp, int(keep.sum()))
            sender = msg.stamps[keep]
            prev = tab.pose_sender_t[rows]
            late = np.isfinite(sender) & np.isfinite(prev) & (sender < prev)
            if late.any():
                self.counters.add("out_of_order", f"poses of robot(s) {ids[keep][late].tolist()} older than the "
                                  "last ones received: dropped", n=int(late.sum()))
            ok_rows = rows[~late]
            tab.pose[ok_rows] = msg.poses[keep][~late]
            tab.pose_t[ok_rows] = t
            tab.pose_sender_t[ok_rows] = sender[~late]
            fresh_batt = msg.batt_volt[keep][~late]
            has_b = np.isfinite(fresh_batt)
            tab.batt[ok_rows[has_b]] = fresh_batt[has_b]
        self.counters.add("pose_messages")

    # ---------------------------------------------------------------- views
    def latest_poses(self) -> PoseSample:
        """Newest pose of every robot ever seen (rows never seen are left out)."""
        with self._lock:
            tab = self._t
            seen = np.isfinite(tab.pose_t)
            order = np.argsort(tab.ids[seen], kind="stable")
            return PoseSample(tab.ids[seen][order].copy(), tab.pose[seen][order].copy(), tab.pose_t[seen][order].copy())

    # Link states as small integer codes (vectorised masks); names only when a status is shown.
    _OK, _STALE, _MISSING, _UNKNOWN, _DUPLICATE = range(5)
    _LINK_NAMES = np.array([LINK_OK, LINK_STALE, LINK_MISSING, LINK_UNKNOWN, LINK_DUPLICATE], dtype=object)

    def _links(self, now: float) -> tuple[NDArray[np.intp], NDArray[np.int8], NDArray[np.float64], NDArray[np.float64]]:
        """Ids, link codes (``_OK`` … ``_DUPLICATE``), pose and status ages (s) of every row."""
        tab = self._t
        last = np.maximum(tab.pose_t, tab.status_t)
        pose_age = now - tab.pose_t
        status_age = now - tab.status_t
        tm = self.timeouts
        link = np.full(len(tab.ids), self._OK, dtype=np.int8)
        link[pose_age > tm.stale_after] = self._STALE
        link[now - last > tm.missing_after] = self._MISSING
        link[~np.isfinite(last)] = self._UNKNOWN
        link[now - tab.duplicate_t < tm.duplicate_hold] = self._DUPLICATE
        return tab.ids, link, pose_age, status_age

    def status(self) -> TransportStatus:
        now = self.clock()
        with self._lock:
            ids, link, _, status_age = self._links(now)
            tab = self._t
            order = np.argsort(ids, kind="stable")
            table = RobotStatusTable(
                # the robot's reported command age, carried forward to now
                ids[order].copy(), tab.batt[order].copy(), tab.charging[order].copy(), (tab.cmd_age + status_age)[order],
                status_age[order], tuple(self._LINK_NAMES[link[order]].tolist()),
            )
        return TransportStatus(self.link.connected, self.link.state, table, self.counters.snapshot(), self.counters.last_error)

    def robots(self) -> NDArray[np.intp]:
        """Ids heard from recently (ok or stale), not missing, never-heard or duplicated; ascending."""
        now = self.clock()
        with self._lock:
            ids, link, _, _ = self._links(now)
            mask = link <= self._STALE
            return np.sort(ids[mask]) if len(ids) else np.empty(0, dtype=np.intp)

    def excluded(self) -> NDArray[np.intp]:
        """Ids that must not be controlled right now (missing or duplicated), ascending."""
        now = self.clock()
        with self._lock:
            ids, link, _, _ = self._links(now)
            mask = (link == self._MISSING) | (link == self._DUPLICATE)
            return np.sort(ids[mask]) if len(ids) else np.empty(0, dtype=np.intp)
