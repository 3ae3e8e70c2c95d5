"""The simulated GRITSBot fleet as a network node: firmware model + MQTT.

Subscribes like the GRITSBot X firmware (``matlab_api/<id>`` for each of its
robots), keeps only the newest command per robot, integrates the unicycle
model every firmware loop (16 ms), brakes after 500 ms without commands, drains
the batteries of robots off the chargers and charges those docked on a slot of
the charging strips, and publishes ``<id>/status`` (``batt_volt``, ``charge_status``) every second and ground-truth poses on
``overhead_tracker/all_robot_pose_data`` at the tracker rate, which the console
can use in place of a camera. ``swarmdeck robots`` runs one in its own process;
several, on several machines with distinct ids, can share one broker.
"""
from __future__ import annotations

import os
import socket
import threading
import time
from collections.abc import Callable
from typing import IO

import numpy as np
from numpy.typing import ArrayLike

from swarmdeck.core.kinematics import GritsBotParams
from swarmdeck.core.service_thread import ServiceThread
from swarmdeck.devices.chargers import ChargerLayout
from swarmdeck.devices.net.firmware import BatteryParams, FirmwareParams, FleetState
from swarmdeck.devices.net.link import MqttLink
from swarmdeck.devices.net.mqtt_config import MqttConfig
from swarmdeck.devices.net.transport import Counters
from swarmdeck.devices.net.wire import WireError, decode_command, encode_poses, encode_status


class FleetNode:
    """Simulated robots behind an MQTT broker.

    Args:
        config: broker and topic layout.
        ids: ``(N,)`` robot ids this node simulates.
        poses: ``(N, 3)`` initial poses.
        firmware, battery, params: models.
        name: node name reported in status messages (default ``fleet-<host>-<pid>``).
        trace: optional text stream; one line ``"<recv_time> <id> <v> <w>"`` per command
            received (monotonic clock), for latency measurements.
        clock: monotonic clock.
        chargers: the arena's charging strips: robots docked on a slot charge and report
            ``charge_status`` true (None: no chargers).
        charge: initial state of charge, ``(N,)`` or scalar in [0, 1].
    """

    def __init__(
        self,
        config: MqttConfig,
        ids: ArrayLike,
        poses: ArrayLike,
        *,
        firmware: FirmwareParams = FirmwareParams(),
        battery: BatteryParams = BatteryParams(),
        params: GritsBotParams = GritsBotParams(),
        name: str | None = None,
        trace: IO[str] | None = None,
        clock: Callable[[], float] = time.monotonic,
        chargers: ChargerLayout | None = None,
        charge: ArrayLike = 1.0,
    ) -> None:
        self.config = config
        self.clock = clock
        self.name = name or f"fleet-{socket.gethostname()}-{os.getpid()}"
        self.counters = Counters()
        self.state = FleetState(ids, poses, clock(), firmware=firmware, battery=battery, params=params,
                                charge=charge, chargers=chargers)
        self.firmware = firmware
        self._lock = threading.Lock()
        self._trace = trace
        self._seq = 0
        self._inbox: dict[int, tuple] = {}
        self._received = [0] * self.state.n
        self._topic_rows: dict[str, int] = {}
        self.link = MqttLink(
            config.with_client_id(config.client_id or f"{self.name}"),
            subscriptions=[config.command_topic(int(i)) for i in self.state.ids],
            on_message=self._on_message,
            counters=self.counters,
            name=self.name,
            clock=clock,
        )
        self._service = ServiceThread(self.run, f"{self.name}-loop")

    # ---------------------------------------------------------------- messages
    def _on_message(self, topic: str, payload: bytes, t: float) -> None:
        """Network thread: check the command and leave it in the inbox (newest per robot wins).

        Kept cheap (no numpy): at 200 robots × 30 Hz this runs 6000 times a second.
        The receive time is taken under the lock, so the loop never advances past
        a command it has not yet seen.
        """
        row = self._topic_rows.get(topic)
        if row is None:
            rid = self.config.robot_id_of_command_topic(topic)
            row = None if rid is None else self.state.index_of(rid)
            if row is None:
                self.counters.add("unknown_topic", f"{self.name}: ignored message on {topic!r} (not one of my robots)")
                return
            self._topic_rows[topic] = row
        try:
            cmd = decode_command(payload)
        except WireError as exc:  # the firmware logs and drops malformed JSON
            self.counters.add("malformed_command", f"{self.name}: robot {int(self.state.ids[row])}: {exc}")
            return
        with self._lock:
            t = self.clock()
            self._inbox[row] = (cmd.v, cmd.w, t, cmd.left_led, cmd.right_led)
            self._received[row] += 1
        if self._trace is not None:
            self._trace.write(f"{t!r} {int(self.state.ids[row])} {cmd.v!r} {cmd.w!r}\n")

    def _drain(self) -> None:
        """Loop thread, lock held: hand the newest command of each robot to the firmware model."""
        if not self._inbox:
            return
        items = self._inbox
        self._inbox = {}
        rows = np.fromiter(items.keys(), np.intp, len(items))
        vals = list(items.values())
        v = np.fromiter((x[0] for x in vals), float, len(vals))
        w = np.fromiter((x[1] for x in vals), float, len(vals))
        t = np.fromiter((x[2] for x in vals), float, len(vals))
        leds = None
        if any(x[3] is not None or x[4] is not None for x in vals):
            leds = self.state.leds[rows].copy()
            for k, x in enumerate(vals):  # only for messages that carry LED colours
                if x[3] is not None:
                    leds[k, 0] = x[3]
                if x[4] is not None:
                    leds[k, 1] = x[4]
        self.state.receive(rows, v, w, t, leds)

    # ---------------------------------------------------------------- loop
    def start(self) -> FleetNode:
        """Connect and run the firmware loop in a background thread."""
        self.link.start()
        self._service.start()
        return self

    def run(self) -> None:
        """The firmware loop (blocks until :meth:`stop`)."""
        fw = self.firmware
        next_loop = self.clock()
        next_pose = next_loop
        next_status = next_loop
        stop = self._service.stop_event
        while not stop.is_set():
            try:
                with self._lock:
                    now = self.clock()
                    self._drain()
                    poses = self.state.advance(now)
                if now >= next_pose:
                    next_pose = max(next_pose + fw.pose_period, now)
                    self._publish_poses(poses, now)
                if now >= next_status:
                    next_status = max(next_status + fw.status_period, now)
                    self._publish_status(now)
            except Exception as exc:  # noqa: BLE001 - keep simulating; the problem is counted and shown
                self.counters.add("loop_errors", f"{self.name}: firmware loop step failed: {exc!r}")
            next_loop += fw.loop_period
            delay = next_loop - self.clock()
            if delay > 0:
                stop.wait(delay)
            else:
                next_loop = self.clock()

    def _publish_poses(self, poses: np.ndarray, now: float) -> None:
        st = self.state
        payload = encode_poses(st.ids, poses, st.battery_voltage(), st.charging(),
                               decimals=self.firmware.pose_decimals, stamp=now)
        self.link.publish(self.config.pose_topic, payload)

    def _publish_status(self, now: float) -> None:
        st = self.state
        with self._lock:
            volts, charging, ages = st.battery_voltage(), st.charging(), st.command_age()
        self._seq += 1
        topics = [self.config.status_topic(int(i)) for i in st.ids]
        payloads = [
            encode_status(b, c, cmd_age=a, seq=self._seq, node=self.name, stamp=now)
            for b, c, a in zip(volts.tolist(), charging.tolist(), ages.tolist())
        ]
        self.link.publish_many(topics, payloads)

    def snapshot(self) -> dict[str, np.ndarray]:
        """A consistent copy of the fleet's state: poses, applied v/w, command age, ids, time."""
        with self._lock:
            self._drain()
            v, w = self.state.applied()
            return {
                "t": np.array(self.state.t),
                "ids": self.state.ids.copy(),
                "poses": self.state.poses.copy(),
                "v": v,
                "w": w,
                "command_age": self.state.command_age(),
                "last_command_time": self.state.cur_t.copy(),
                "timeouts": self.state.timeouts.copy(),
                "commands_received": np.asarray(self._received, dtype=np.int64),
                "charge": self.state.charge.copy(),
                "charging": self.state.charging(),
            }

    def stop(self) -> None:
        """Stop the loop and disconnect (idempotent)."""
        self._service.stop()
        self.link.close()
