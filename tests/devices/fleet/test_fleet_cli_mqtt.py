"""`swarmdeck fleet release --robots-via mqtt://…` docks a simulated GRITSBot fleet on a real mosquitto broker:
every robot on a charger slot, the arena ready, and the firmware reporting charge_status true."""
from __future__ import annotations

import json

import numpy as np
import pytest
from mqtt_broker import wait_until

from swarmdeck.console.cli import main
from swarmdeck.devices.fleet import ChargerLayout
from swarmdeck.devices.net.fleet import FleetNode
from swarmdeck.devices.net.mqtt_config import parse_broker_url

pytestmark = pytest.mark.mqtt


def test_release_docks_every_robot_over_mqtt(mosquitto, capsys):
    layout = ChargerLayout()
    floor = np.array([[-0.9, -0.45, 2.0], [0.3, 0.5, -1.0], [1.0, -0.3, 0.5]])
    fleet = FleetNode(parse_broker_url(mosquitto.url), [0, 1, 2], floor, chargers=layout, charge=0.7,
                      name="fleet-release").start()
    try:
        assert main(["fleet", "release", "--robots-via", mosquitto.url, "--json", "--wait", "2"]) == 0
        doc = json.loads(capsys.readouterr().out)
        assert doc["ok"] and doc["ready"] and doc["collisions"] == 0 and sorted(doc["robots"]) == [0, 1, 2]
        truth = fleet.snapshot()["poses"]  # the fleet's own ground truth, not what the console saw
        assert (layout.docked_slot(truth) >= 0).all()
        wait_until(lambda: fleet.snapshot()["charging"].all(), 10, "charging on the strips")
        assert main(["fleet", "status", "--robots-via", mosquitto.url, "--wait", "2"]) == 0
        assert "3/3 docked · ready" in capsys.readouterr().out
    finally:
        fleet.stop()
