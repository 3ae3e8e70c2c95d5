"""Hostile experiment scripts shared by the sandbox's and the portal's verification tests."""

STALE_FOREVER = """
def experiment(arena):
    while True:
        arena.backend._k -= 1  # answer every tick with the previous tick's number
        arena.step()
"""

FIVE_HUNDRED = """
import numpy as np
import rps.robotarium as robotarium
x, y = np.meshgrid(np.linspace(-1.5, 1.5, 25), np.linspace(-0.95, 0.95, 20))
r = robotarium.Robotarium(number_of_robots=500, initial_conditions=np.vstack((x.ravel(), y.ravel(), np.zeros(500))))
while True:
    r.set_velocities(np.arange(500), np.zeros((2, 500)))
    r.step()
"""
