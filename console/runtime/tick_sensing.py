"""The robots' sensors in the console loop (``[console] sensors = true``, ``swarmdeck console --sensors``; issue 28.1).

:class:`TickSensing` keeps one :class:`~swarmdeck.sensing.Sensors` (Robotarium 2.0's seven ToF sensors, encoders,
IMU, LEDs; noise seeded from the loop's ``seed``) and gives each tick's Frame what the robots sensed at that tick's
poses: the ToF rays cast from them, the encoders advanced by the previous tick's commands (the motion that brought
the robots there). Robots whose firmware reports readings (:class:`~swarmdeck.core.ports.ReportsSensors`) give
theirs. A change in the number of robots starts the sensors afresh.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from swarmdeck.console.runtime.params import LoopConfig
from swarmdeck.console.runtime.sensors_frame import SensorsFrame
from swarmdeck.core.ports import ReportsSensors
from swarmdeck.sensing import DistanceSensorConfig, SensingConfig, SensorReadings, Sensors

__all__ = ["TickSensing"]

#: The console's sensors' noise stream beside the simulator's (seeded with (seed, this)).
_CONSOLE_SENSING_STREAM = 0x5E46


class TickSensing:
    """Each tick's :class:`SensorsFrame` (see the module docstring)."""

    def __init__(self, config: LoopConfig, sensing: SensingConfig | None = None) -> None:
        self.config = config
        self.sensing = sensing if sensing is not None else SensingConfig(distance=DistanceSensorConfig())
        self._sensors: Sensors | None = None
        self._v = np.zeros(0)
        self._w = np.zeros(0)

    def _fresh(self, n: int) -> Sensors:
        seed = self.config.seed
        rng = np.random.default_rng(None if seed is None else [int(seed), _CONSOLE_SENSING_STREAM])
        self._v, self._w = np.zeros(n), np.zeros(n)
        return Sensors(n, self.sensing, rng=rng, bounds=self.config.bounds)

    def read(self, source: object, poses: NDArray[np.float64], v: NDArray[np.float64], w: NDArray[np.float64]
             ) -> SensorsFrame:
        """What the robots sensed at ``poses`` ``(N, 3)``; ``v``, ``w`` ``(N,)``: this tick's commands (they move
        the encoders of the next tick's readings)."""
        n = len(poses)
        readings: SensorReadings | None = source.sensor_readings() if isinstance(source, ReportsSensors) else None
        if readings is None:
            if self._sensors is None or self._sensors.n != n:
                self._sensors = self._fresh(n)
            readings = self._sensors.update(poses, self._v, self._w, self.config.dt)
        self._v, self._w = np.array(v, dtype=float), np.array(w, dtype=float)
        return SensorsFrame.of(readings, self.sensing)
