"""examples/sensor_avoidance.py: robots that only see their own ToF readings wander without leaving the arena,
turn away from what they see, and show it on their LEDs."""
from __future__ import annotations

import numpy as np

from swarmdeck.devices import Arena
from swarmdeck.devices.simulator import ArenaConfig
from swarmdeck.examples.sensor_avoidance import experiment


def test_the_wanderers_turn_away_and_stay_inside():
    arena = Arena(6, config=ArenaConfig(seed=2), duration=8.0, safety=False)
    result = experiment(arena)
    assert result["robot-steps spent turning away"] > 0
    report = arena.report().to_dict()["validation"]
    assert report["steps_with_boundary"] == 0, report
    leds = arena.sense().leds
    assert {tuple(c) for c in leds.tolist()} <= {(0, 200, 0), (220, 0, 0)}
    assert np.isfinite(arena.poses()).all()
