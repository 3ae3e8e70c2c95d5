"""Camera tracking and real (or fleet-simulated) robots for the loop: pose sources and command sinks.

* ``--camera synthetic|INDEX|FILE`` → :class:`TrackedPoseSource`, a
  ``swarmdeck.tracking.CameraPoseSource`` read once per tick. ``synthetic``
  renders the robots the command sink knows (the simulator's truth, or the poses
  the MQTT robots report) through the synthetic overhead camera, so the whole
  camera → ArUco → homography → poses path runs with no hardware.
* ``--robots-via mqtt://HOST:PORT`` → :class:`StreamerSink` (an
  ``MqttTransport`` behind the ``CommandStreamer`` watchdogs: stale poses, stale
  inputs and missing robots get zero) and, without a camera, poses from the
  robots' pose topic (:class:`TransportPoseSource`).

Robots without a fresh pose are "not seen": the loop commands them zero and the
barrier treats them as fixed obstacles.
"""
from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmdeck.console.robots import SensedPoses

STALE_AFTER = 0.1  # s: poses older than this are not used for control (Robotarium monitor, REFERENCE.md §9)


def _finite_or_zero(poses: NDArray[np.float64]) -> NDArray[np.float64]:
    out = np.array(poses, dtype=float)
    out[~np.isfinite(out)] = 0.0
    return out


class TrackedPoseSource:
    """Poses from an overhead camera through ``swarmdeck.tracking`` (one frame per tick).

    Args:
        camera: a ``tracking.CameraPoseSource``.
        ids: the robot ids the loop controls (the tracker lists them even before they are seen).
    """

    def __init__(self, camera: Any, ids: NDArray[np.int64], name: str = "camera") -> None:
        self.camera = camera
        self.ids = np.asarray(ids, dtype=np.int64)
        self.name = name
        self._last = np.zeros((len(self.ids), 3))

    def read(self, now: float) -> SensedPoses:
        tp = self.camera.read(now)
        poses = np.array(self._last)
        seen = np.zeros(len(self.ids), dtype=bool)
        if len(tp.ids):
            pos = np.searchsorted(tp.ids, self.ids)
            pos_c = np.minimum(pos, len(tp.ids) - 1)
            hit = tp.ids[pos_c] == self.ids
            rows = pos_c[hit]
            got = tp.poses[rows]
            ok = np.all(np.isfinite(got), axis=1)
            stale = tp.stale[rows] if len(tp.stale) == len(tp.ids) else np.zeros(len(rows), dtype=bool)
            where = np.flatnonzero(hit)
            poses[where[ok]] = got[ok]
            seen[where] = ok & ~stale
        self._last = poses
        return SensedPoses(self.ids, poses, seen)

    def health(self) -> str:
        return self.camera.status_line()

    def close(self) -> None:
        close = getattr(self.camera.source, "close", None)
        if close is not None:
            close()


class TransportPoseSource:
    """Poses the robots' transport receives (the tracker topic ``overhead_tracker/all_robot_pose_data``)."""

    def __init__(self, transport: Any, ids: NDArray[np.int64], clock: Callable[[], float] = time.monotonic) -> None:
        self.transport = transport
        self.ids = np.asarray(ids, dtype=np.int64)
        self.clock = clock
        self.name = "robots' pose topic"
        self._fresh = 0

    def read(self, now: float) -> SensedPoses:
        sample = self.transport.latest_poses()
        poses, stamps = sample.select(self.ids)
        seen = np.all(np.isfinite(poses), axis=1) & (self.clock() - stamps <= STALE_AFTER)
        self._fresh = int(seen.sum())
        return SensedPoses(self.ids, _finite_or_zero(poses), seen)

    def truth(self, now: float) -> NDArray[np.float64]:
        """Latest reported poses (N, 3) (for the synthetic camera); never-seen robots at the origin."""
        poses, _ = self.transport.latest_poses().select(self.ids)
        return _finite_or_zero(poses)

    def health(self) -> str:
        return f"poses {self._fresh}/{len(self.ids)} fresh"


class StreamerSink:
    """Commands to robots over a transport through the ``CommandStreamer`` watchdogs.

    ``send`` submits the tick's commands and streams them at once; the streamer's own
    thread keeps sending (zeros once the input goes stale) if the loop stalls.
    """

    def __init__(self, transport: Any, streamer: Any, ids: NDArray[np.int64], name: str) -> None:
        self.transport, self.streamer = transport, streamer
        self.ids = np.asarray(ids, dtype=np.int64)
        self.name = name

    def send(self, ids: NDArray[np.int64], v: NDArray[np.float64], w: NDArray[np.float64]) -> None:
        self.streamer.submit(ids, v, w)
        self.streamer.tick()

    def hold(self) -> None:
        self.send(self.ids, np.zeros(len(self.ids)), np.zeros(len(self.ids)))

    def health(self) -> str:
        h = self.streamer.health()
        excl = f", excluded {h.excluded.tolist()}" if len(h.excluded) else ""
        return f"{self.name}: {h.state}{excl}"

    def close(self) -> None:
        try:
            self.streamer.stop()
        finally:
            self.transport.close()


def mqtt_robots(url: str, ids: NDArray[np.int64]) -> tuple[StreamerSink, TransportPoseSource]:
    """Connect to the broker at ``url``: a command sink and the robots' pose topic as a pose source.

    Raises ValueError for a malformed URL (the message says the expected form).
    """
    from swarmdeck.devices.mqtt_config import parse_broker_url
    from swarmdeck.devices.streamer import CommandStreamer
    from swarmdeck.devices.transport_mqtt import MqttTransport

    config = parse_broker_url(url)
    transport = MqttTransport(config, ids=ids).start()
    streamer = CommandStreamer(transport, poses=transport).start()
    return StreamerSink(transport, streamer, ids, f"mqtt {config.host}:{config.port}"), TransportPoseSource(transport, ids)


def camera_source(spec: str, ids: NDArray[np.int64], truth: Callable[[float], NDArray[np.float64]] | None,
                  bounds: tuple[float, float, float, float]) -> TrackedPoseSource:
    """A tracked pose source for ``--camera`` ``synthetic`` (rendering ``truth(now)``), a webcam index,
    a stream URL, a folder of images or a video file. Raises ValueError naming what is wrong."""
    from swarmdeck.tracking import (CameraCalibration, CameraPoseSource, SyntheticCamera, SyntheticCameraConfig,
                                    Tracker, TrackerConfig, open_source)

    expected = tuple(int(i) for i in ids)
    if spec == "synthetic":
        if truth is None:
            raise ValueError("--camera synthetic needs robots to render (the simulation or --robots-via)")
        cam = SyntheticCamera(truth, ids=expected, config=SyntheticCameraConfig(bounds=bounds))
        cal = CameraCalibration.from_camera(cam.renderer.camera)
        tracker = Tracker(TrackerConfig(calibration=cal, expected_ids=expected, bounds=bounds))
        return TrackedPoseSource(CameraPoseSource(cam, tracker), ids, "synthetic camera")
    src = open_source(spec)
    tracker = Tracker(TrackerConfig(expected_ids=expected, bounds=bounds))
    return TrackedPoseSource(CameraPoseSource(src, tracker), ids, f"camera {spec}")
