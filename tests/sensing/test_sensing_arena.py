"""The sensors at the Arena level (issue 28.1): off unless asked for (a clear error from sense()), readings after
every step with the same seed giving the same readings, LEDs set at once, and robots whose firmware reports
readings (core.ports.ReportsSensors) giving theirs instead of simulated ones."""
from __future__ import annotations

import numpy as np
import pytest

from swarmdeck.core.ports import ReportsSensors
from swarmdeck.devices import Arena
from swarmdeck.devices.simulated_robots import SimulatedRobots
from swarmdeck.devices.simulator import ArenaConfig, SimulatedArena
from swarmdeck.sensing import DistanceSensorConfig, SensingConfig, SensingConfigError, SensorReadings

IC = np.array([[-0.5, 0.0, 0.0], [-0.1, 0.0, np.pi], [0.7, 0.5, 1.0]])


def _run(seed: int) -> list[np.ndarray]:
    arena = Arena(initial_conditions=IC, config=ArenaConfig(seed=seed), sensing=SensingConfig(
        distance=DistanceSensorConfig()))
    out = []
    for _ in range(10):
        arena.set_unicycle(np.full(3, 0.05), np.zeros(3))
        arena.step()
        out.append(arena.sense().distances)
    return out


def test_no_sensors_unless_asked_for():
    arena = Arena(2, config=ArenaConfig(seed=1))
    with pytest.raises(RuntimeError, match=r"no sensors: build it with Arena\(\.\.\., sensing=SensingConfig"):
        arena.sense()
    with pytest.raises(RuntimeError, match="no sensors"):
        arena.set_leds(np.zeros((2, 3)))
    with pytest.raises(SensingConfigError, match="sensing must be a SensingConfig"):
        Arena(2, sensing=DistanceSensorConfig())  # type: ignore[arg-type]


def test_the_same_seed_gives_the_same_readings():
    a, b, c = _run(4), _run(4), _run(5)
    assert all(np.array_equal(x, y) for x, y in zip(a, b))
    assert not all(np.array_equal(x, y) for x, y in zip(a, c))


def test_leds_show_at_once_and_ids_select_robots():
    arena = Arena(initial_conditions=IC, sensing=SensingConfig())
    arena.set_leds(np.array([[0, 0, 255]]), ids=[2])
    assert arena.sense().leds.tolist() == [[0, 0, 0], [0, 0, 0], [0, 0, 255]]
    with pytest.raises(ValueError, match="unknown robot id"):
        arena.set_leds(np.array([[0, 0, 255]]), ids=[7])


class FirmwareRobots(SimulatedRobots):
    """Simulated robots standing in for firmware that reports its own ToF readings (0.42 m everywhere)."""

    def sensor_readings(self) -> SensorReadings:
        n = self.sim.n_robots
        return SensorReadings(distances=np.full((n, 7), 0.42))


def test_robots_that_report_readings_give_theirs():
    robots = FirmwareRobots(sim=SimulatedArena(None, IC, config=ArenaConfig(seed=1)))
    assert isinstance(robots, ReportsSensors)
    arena = Arena(backend=robots, sensing=SensingConfig(distance=DistanceSensorConfig()))
    arena.step()
    assert (arena.sense().distances == 0.42).all()
