"""Hostile experiment scripts shared by the sandbox's and the portal's verification tests."""

STALE_FOREVER = """
def experiment(arena):
    while True:
        arena.backend._k -= 1  # answer every tick with the previous tick's number
        arena.step()
"""

# an Arena (not rps's Robotarium, which refuses more than 50 robots itself, as rps does) of 500 robots
FIVE_HUNDRED = """
import numpy as np
from swarmdeck.devices import Arena
x, y = np.meshgrid(np.linspace(-1.5, 1.5, 25), np.linspace(-0.95, 0.95, 20))
arena = Arena(500, initial_conditions=np.column_stack((x.ravel(), y.ravel(), np.zeros(500))))
while True:
    arena.step_unicycle(np.zeros(500), np.zeros(500))
"""
