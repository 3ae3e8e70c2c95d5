"""Wander with the ToF sensors only (issue 28.1): each robot drives ahead and turns away from whatever its three
front sensors see within 0.3 m — other robots or the walls — using nothing but its own readings; its LED shows
green while the way is clear and red while it turns.

    swarmdeck run examples/sensor_avoidance.py --robots 8 --duration 30 --record wander.mcap
    swarmdeck play wander.mcap        # the rays, their end points and the LEDs (layer "sensors")
"""
import numpy as np

from swarmdeck.devices import Arena
from swarmdeck.sensing import DistanceSensorConfig, SensingConfig

FRONT = [2, 3, 4]  # the sensors at +45°, 0°, −45° (Robotarium 2.0's layout)
CLEAR = np.array([0, 200, 0])
TURNING = np.array([220, 0, 0])


def experiment(arena: Arena) -> dict:
    """Wander until the arena's duration (or 20 s) is over; return how often the robots turned away."""
    if arena.sensors is None or arena.sensors.config.distance is None:
        arena.use_sensors(SensingConfig(distance=DistanceSensorConfig(walls=True)))
    end = arena.duration if arena.duration is not None else 20.0
    turning_steps = 0
    while arena.time < end - 1e-9:
        distances = arena.sense().distances  # (N, 7) m; −1: nothing in range (or a dropout)
        assert distances is not None  # the arena has ToF sensors (above)
        d = distances[:, FRONT]
        near = np.where(d >= 0, d, np.inf)
        blocked = near.min(axis=1) < 0.3
        # turn away from the nearer side: left sensor (+45°) closer → turn right
        side = np.where(near[:, 0] < near[:, 2], -1.0, 1.0)
        arena.set_unicycle(np.where(blocked, 0.0, 0.12), np.where(blocked, 1.5 * side, 0.0))
        arena.set_leds(np.where(blocked[:, None], TURNING, CLEAR))
        turning_steps += int(blocked.sum())
        arena.step()
    return {"robot-steps spent turning away": turning_steps}


if __name__ == "__main__":
    print(experiment(Arena(8)))
