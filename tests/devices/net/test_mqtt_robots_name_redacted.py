"""The console's MQTT robots are named by their broker URL without its password (the name reaches status
lines, logs and recordings)."""
from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from swarmdeck.console.runtime.hardware import mqtt_robots

pytestmark = pytest.mark.mqtt


def test_the_robots_name_carries_the_user_but_not_the_password(mosquitto):
    fleet = subprocess.Popen(
        [sys.executable, "-c", "import sys; from swarmdeck.console.cli import main; sys.exit(main())", "robots",
         "--broker", mosquitto.url, "--robots", "2", "--seed", "3", "--quiet"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    robots = None
    try:
        url = mosquitto.url.replace("mqtt://", "mqtt://alice:s3cret-pw@", 1)
        robots, _ = mqtt_robots(url, np.arange(2), wait_for_poses=15)
        assert "s3cret-pw" not in robots.name
        assert "alice:***@" in robots.name
    finally:
        if robots is not None:
            robots.close()
        fleet.terminate()
        fleet.communicate(timeout=10)
