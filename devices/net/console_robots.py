"""Networked robots as robot ports: the console loop's (``--robots-via mqtt://…``) and the Arena's.

:class:`NetworkRobots` is both robot ports of :mod:`swarmdeck.core.ports` —
the ``PoseSource`` (``read(now) -> SensedPoses``) and the ``CommandSink``
(``send(ids, v, w)`` / ``hold()`` / ``health()`` / ``close()`` / ``obstacles()``)
— on top of any :class:`~swarmdeck.devices.net.transport.RobotTransport` that is
also a :class:`~swarmdeck.devices.net.transport.PoseFeed` (the MQTT transport: poses
from ``overhead_tracker/all_robot_pose_data``, i.e. ``swarmdeck robots`` or a
real tracker). Commands pass through a
:class:`~swarmdeck.devices.net.streamer.CommandStreamer`, which also keeps
streaming (zeros, once inputs are stale) from a background thread if the loop
stalls.

The same class drives an experiment on real robots: ``Arena(backend=NetworkRobots.connect(url,
n_robots=6))`` (the Arena paces each step to one period of wall time). As the simulator does, every
``send`` stops robots whose command is not finite and applies the wheel limits by one uniform scale
per robot (curvature kept) before anything goes out: real firmware clips each wheel on its own,
which would change the direction of motion (:attr:`NetworkRobots.saturated`, :attr:`NetworkRobots.invalid`
count them).

Robots the transport reports missing or duplicated are left out of
:meth:`NetworkRobots.read` (excluded from control) and returned by
:meth:`NetworkRobots.obstacles` at their last known position, for
``SafetyFilter.filter(points, nominal, obstacles=robots.obstacles())``.
"""
from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.kinematics import GritsBotParams, limit_unicycle
from swarmdeck.core.ports import SensedPoses
from swarmdeck.devices.net.mqtt_config import parse_broker_url, redact_url
from swarmdeck.devices.net.streamer import CommandStreamer, StreamerConfig
from swarmdeck.devices.net.transport_mqtt import LinkTimeouts, MqttTransport


class NetworkRobots:
    """Robots behind a transport, for the console loop.

    Args:
        transport: a started transport that also gives poses (``latest_poses()``).
        ids: robot ids to control (None: every robot the transport hears of).
        streamer: watchdog thresholds and the background streaming period.
        background: keep a background streaming thread (zeros flow even if the loop hangs).
        clock: the transport's monotonic clock.
        name: shown in the console's status bar.
        params: the robot model (its wheel limits apply to every command sent).
        simulated_time: the transport runs on a simulated clock (the in-process transport): readings
            carry ``clock()`` as the robots' time, so an Arena over them does not pace itself.
    """

    def __init__(
        self,
        transport: MqttTransport,
        ids: ArrayLike | None = None,
        *,
        streamer: StreamerConfig = StreamerConfig(),
        background: bool = True,
        clock: Callable[[], float] = time.monotonic,
        name: str = "mqtt",
        params: GritsBotParams = GritsBotParams(),
        simulated_time: bool = False,
    ) -> None:
        self.transport = transport
        self.name = name
        self.clock = clock
        self.params = params
        self.simulated_time = bool(simulated_time)
        self.saturated = 0  # robot-commands the wheel limits scaled down
        self.invalid = 0  # robot-commands that were NaN/inf (sent as zero)
        self.ids = None if ids is None else np.asarray(ids, dtype=np.int64).reshape(-1).copy()
        self._leds: dict[int, tuple[int, int, int]] = {}  # robot id -> the RGB the experiment set (ShowsLeds)
        self.streamer = CommandStreamer(transport, transport, streamer, clock)
        if background:
            self.streamer.start()

    @classmethod
    def connect(
        cls,
        url: str,
        ids: ArrayLike | None = None,
        *,
        n_robots: int | None = None,
        wait_for_poses: float = 5.0,
        partial: bool = False,
        name: str | None = None,
        timeouts: LinkTimeouts = LinkTimeouts(),
        streamer: StreamerConfig = StreamerConfig(),
        **mqtt: object,
    ) -> NetworkRobots:
        """Connect to ``url`` and wait up to ``wait_for_poses`` s for the first pose of every robot.

        ``ids`` (or ``n_robots`` for ids 0..N−1) fixes the robots to control; with neither,
        every robot heard of within ``wait_for_poses`` is used. ``partial``: with ``ids``, go on
        once the wait is over if at least one of them reported (the others stay out of readings
        until they do: one silent robot does not keep a fleet from working). ``name``: the status
        line's name (default ``mqtt <url without password>``). Extra keywords go to
        :class:`~swarmdeck.devices.net.mqtt_config.MqttConfig` (``qos``, ``protocol``, ``ca_certs``, …).

        Raises:
            ValueError: bad URL, or no robot (or not every named robot) sent a pose in time;
                the message names the missing ids and the link state.
        """
        if ids is None and n_robots is not None:
            ids = np.arange(int(n_robots))
        cfg = parse_broker_url(url, **mqtt)
        transport = MqttTransport(cfg, ids=ids, timeouts=timeouts).start()
        try:
            deadline = time.monotonic() + wait_for_poses
            while True:
                seen = transport.latest_poses().ids
                if ids is not None:
                    missing = np.setdiff1d(np.asarray(ids, dtype=np.int64), seen)
                    if not len(missing) or (partial and len(seen) and time.monotonic() > deadline):
                        break
                elif len(seen) and time.monotonic() > deadline - wait_for_poses / 2:
                    break  # robots heard of; half the wait spent collecting stragglers
                if time.monotonic() > deadline:
                    st = transport.status().state
                    what = f"robot id(s) {missing.tolist()}" if ids is not None else "any robot"
                    raise ValueError(f"no pose from {what} on {cfg.url} within {wait_for_poses} s ({st}); "
                                     f"is `swarmdeck robots --broker {redact_url(url)}` (or the tracker) running?")
                time.sleep(0.02)
        except BaseException:
            transport.close()
            raise
        return cls(transport, ids, streamer=streamer, name=name if name is not None else f"mqtt {redact_url(url)}")

    # ---------------------------------------------------------------- pose source
    def read(self, now: float | None = None) -> SensedPoses:
        """Robots under control (not missing/duplicated) with their last known poses and freshness,
        and their last reported battery voltage (NaN: none yet) and charging state.

        ``now`` (the loop's clock) is accepted for the PoseSource protocol and not used:
        freshness is judged on this transport's own monotonic clock.
        """
        sample = self.transport.latest_poses()
        ids = sample.ids if self.ids is None else self.ids
        ids = np.setdiff1d(ids, self.transport.excluded(), assume_unique=True)
        poses, stamps = sample.select(ids)
        known = np.all(np.isfinite(poses), axis=1)
        ids, poses, stamps = ids[known], poses[known], stamps[known]
        seen = (self.clock() - stamps) <= self.streamer.config.pose_timeout
        battery, charging = self.transport.status().robots.battery_of(ids)
        return SensedPoses(ids.astype(np.int64), poses, seen, battery=battery, charging=charging,
                           time=self.clock() if self.simulated_time else None)

    def truth(self, now: float | None = None) -> NDArray[np.float64]:
        """Latest reported poses ``(N, 3)`` of the robots under control, unknown ones at 0 (what a
        synthetic overhead camera renders, ``--camera synthetic``)."""
        out = np.array(self.read().poses, dtype=float)
        out[~np.isfinite(out)] = 0.0
        return out

    def obstacles(self) -> NDArray[np.float64]:
        """``(M, 2)`` last known centres of robots excluded from control (fixed obstacles), m."""
        return self.streamer.obstacles()

    # ---------------------------------------------------------------- command sink
    def set_leds(self, ids: ArrayLike, rgb: ArrayLike) -> None:
        """The robots' LEDs (:class:`~swarmdeck.core.ports.ShowsLeds`): ``rgb`` ``(K, 3)`` 0…255 for ``ids``
        ``(K,)``, sent with every command from now on (both LEDs of a GRITSBot)."""
        ids_arr = np.asarray(ids, dtype=np.int64).reshape(-1)
        colours = np.clip(np.asarray(rgb, dtype=float).reshape(-1, 3), 0, 255).astype(np.uint8)
        if len(colours) != len(ids_arr):
            raise ValueError(f"LED colours must have one (R, G, B) row per id ({len(ids_arr)}), got {len(colours)}")
        for i, c in zip(ids_arr.tolist(), colours.tolist()):  # once per call, not per tick
            self._leds[int(i)] = (int(c[0]), int(c[1]), int(c[2]))

    def send(self, ids: ArrayLike, v: ArrayLike, w: ArrayLike, leds: ArrayLike | None = None) -> None:
        """Hand this tick's commands to the streamer and send them at once (watchdogs applied).

        Non-finite commands become zero and the wheel limits are applied by one uniform scale per
        robot first (module docstring); the caller's arrays are not changed.
        """
        v = np.asarray(v, dtype=float).reshape(-1)
        w = np.asarray(w, dtype=float).reshape(-1)
        bad = ~(np.isfinite(v) & np.isfinite(w))
        v, w, saturated = limit_unicycle(np.where(bad, 0.0, v), np.where(bad, 0.0, w), self.params)
        self.saturated += int(saturated.sum())
        self.invalid += int(bad.sum())
        if leds is None and self._leds:  # the LEDs the experiment set (ShowsLeds), unlit for the others
            ids_arr = np.asarray(ids, dtype=np.int64).reshape(-1)
            leds = np.array([self._leds.get(int(i), (0, 0, 0)) for i in ids_arr.tolist()], dtype=np.uint8).reshape(-1, 3)
        self.streamer.submit(ids, v, w, leds)
        self.streamer.tick()

    def hold(self) -> None:
        """Paused: every robot under control gets zero."""
        ids = self.read().ids
        self.streamer.submit(ids, np.zeros(len(ids)), np.zeros(len(ids)))
        self.streamer.tick()

    def health(self) -> str:
        """One line for the status bar: link, robots ok/stale/missing, battery, command age, problems."""
        st = self.transport.status()
        links = st.robots.link
        counts = {k: links.count(k) for k in ("ok", "stale", "missing", "duplicate", "unknown") if links.count(k)}
        batt = st.robots.battery_voltage[np.isfinite(st.robots.battery_voltage)]
        age = st.robots.command_age[np.isfinite(st.robots.command_age)]
        parts = [("connected" if st.connected else "DISCONNECTED: " + st.state),
                 ", ".join(f"{v} {k}" for k, v in counts.items()) or "no robots"]
        if len(batt):
            parts.append(f"battery min {batt.min():.2f} V")
        if len(age):
            parts.append(f"cmd age max {age.max():.2f} s")
        c = self.streamer.counters.snapshot()
        bad = {k: v for k, v in st.counters.items()
               if k not in ("commands_sent", "pose_messages", "status_received", "reconnects")}
        if bad or c.get("undelivered_ticks"):
            parts.append(f"problems {dict(bad, undelivered_ticks=c.get('undelivered_ticks', 0))}")
        return "; ".join(parts)

    def robot_health(self) -> dict:
        """Per robot ``{"<id>": {link, battery_voltage, charging, command_age, status_age}}`` (JSON-able)."""
        return self.transport.status().robots.to_dict()

    def events(self) -> tuple[str, ...]:
        """Recent watchdog events (stale poses/inputs, exclusions, delivery lost/regained)."""
        return tuple(self.streamer.events)

    def close(self) -> None:
        """Stop streaming, command zero once, disconnect."""
        self.streamer.stop()
        self.transport.close()
