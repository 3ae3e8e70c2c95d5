"""Camera tracking and real (or fleet-simulated) robots for the loop: pose sources and command sinks.

The ports are :mod:`swarmdeck.core.ports`'s ``PoseSource`` and ``CommandSink``.

* ``--camera synthetic|INDEX|FILE`` → ``swarmdeck.tracking.TrackedPoseSource``, a
  ``swarmdeck.tracking.CameraPoseSource`` read once per tick. ``synthetic``
  renders the robots the command sink knows (the simulator's truth, or the poses
  the MQTT robots report) through the synthetic overhead camera, so the whole
  camera → ArUco → homography → poses path runs with no hardware.
* ``--robots-via mqtt://HOST:PORT`` → ``devices.net.console_robots.NetworkRobots``
  as the command sink (an ``MqttTransport`` behind the ``CommandStreamer``
  watchdogs: stale poses, stale inputs and missing robots get zero; missing
  robots become barrier obstacles) and, without a camera, poses from the
  robots' pose topic (:class:`NetworkPoseSource`).

Robots without a fresh pose are "not seen": the loop commands them zero and the
barrier treats them as fixed obstacles.
"""
from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from swarmdeck.core.ports import SensedPoses

if TYPE_CHECKING:
    from swarmdeck.tracking import TrackedPoseSource


def _finite_or_zero(poses: NDArray[np.float64]) -> NDArray[np.float64]:
    out = np.array(poses, dtype=float)
    out[~np.isfinite(out)] = 0.0
    return out


class NetworkPoseSource:
    """The pose side of ``devices.net.console_robots.NetworkRobots`` (the robots' pose topic) for the loop.

    Robots the transport reports missing or duplicated are left out (excluded from control);
    the sink's ``obstacles()`` gives their last positions to the barrier.
    """

    def __init__(self, robots: Any) -> None:
        self.robots = robots
        self.name = "robots' pose topic"

    def read(self, now: float) -> SensedPoses:
        return self.robots.read()

    def truth(self, now: float) -> NDArray[np.float64]:
        """Latest reported poses (N, 3) of the robots under control (for the synthetic camera)."""
        return _finite_or_zero(self.robots.read().poses)

    def health(self) -> str:
        return self.robots.health()


def mqtt_robots(url: str, ids: NDArray[np.int64], wait_for_poses: float = 5.0) -> tuple[Any, NetworkPoseSource]:
    """Connect to the broker at ``url`` (GRITSBots, or ``swarmdeck robots``): the command sink (a
    ``NetworkRobots``: streamer watchdogs, obstacles for excluded robots) and its pose source.

    Raises ValueError for a malformed URL or robots that sent no pose within ``wait_for_poses`` s.
    """
    from swarmdeck.devices.net.console_robots import NetworkRobots
    from swarmdeck.devices.net.mqtt_config import redact_url

    robots = NetworkRobots.connect(url, ids=ids, wait_for_poses=wait_for_poses)
    robots.name = f"mqtt {redact_url(url)}"  # shown in status lines, logs and recordings
    return robots, NetworkPoseSource(robots)


def camera_source(spec: str, ids: NDArray[np.int64], truth: Callable[[float], NDArray[np.float64]] | None,
                  bounds: tuple[float, float, float, float]) -> TrackedPoseSource:
    """A tracked pose source for ``--camera`` ``synthetic`` (rendering ``truth(now)``), a webcam index,
    a stream URL, a folder of images or a video file. Raises ValueError naming what is wrong."""
    from swarmdeck.tracking import (
        CameraCalibration,
        CameraPoseSource,
        SyntheticCamera,
        SyntheticCameraConfig,
        TrackedPoseSource,
        Tracker,
        TrackerConfig,
        open_source,
    )

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
