"""A robot that stops reporting during a set-up over MQTT (its fleet process dies; real mosquitto): the set-up
stops every robot and names the robot; `swarmdeck fleet status` shows the fleet (battery, charging, docked)."""
from __future__ import annotations

import json
import time

import numpy as np
import pytest
from mqtt_broker import wait_until

from swarmdeck.console.cli import main
from swarmdeck.console.runtime import fleet_upkeep as fu
from swarmdeck.console.runtime.hardware import mqtt_robots
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.devices.clock import RealTimePacer
from swarmdeck.devices.fleet import ChargerLayout
from swarmdeck.devices.net.fleet import FleetNode
from swarmdeck.devices.net.mqtt_config import parse_broker_url

pytestmark = pytest.mark.mqtt
CHARGERS = ChargerLayout()


def test_a_robot_that_stops_reporting_stops_the_setup_and_is_named(mosquitto, capsys):
    cfg = parse_broker_url(mosquitto.url)
    docks = CHARGERS.dock_poses()
    stay = FleetNode(cfg, [0, 1], docks[[0, 1]], chargers=CHARGERS, charge=0.2, name="fleet-stay").start()
    moving = FleetNode(cfg, [2, 3], docks[[2, 3]], chargers=CHARGERS, charge=0.9, name="fleet-dies").start()
    loop = None
    try:
        wait_until(lambda: main(["fleet", "status", "--robots-via", mosquitto.url, "--json", "--wait", "1"]) == 0
                   and len(json.loads(capsys.readouterr().out)["robots"]) == 4, 30, "four robots in fleet status")
        rows = {}
        # charge_status arrives once a second on the status topic: ask again until every robot shows it
        def charging_all() -> bool:
            assert main(["fleet", "status", "--robots-via", mosquitto.url, "--json", "--wait", "1"]) == 0
            rows.update({r["id"]: r for r in json.loads(capsys.readouterr().out)["robots"]})
            return all(r["charging"] for r in rows.values())
        wait_until(charging_all, 30, "charging reported")
        assert [rows[i]["docked_slot"] for i in range(4)] == [0, 1, 2, 3]
        assert rows[0]["charge"] == pytest.approx(0.2, abs=0.01) and rows[3]["charge"] == pytest.approx(0.9, abs=0.01)

        sink, source = mqtt_robots(mosquitto.url, np.arange(4), wait_for_poses=15)
        loop = ControlLoop(LoopConfig(n_robots=4), source=source, sink=sink, clock=time.monotonic)
        loop.pause()
        frame = wait_until(lambda: (f := loop.tick()).charging.all() and f, 20, "charging in a Frame")
        view = fu.FleetView.of(frame, fu.status_ages(sink, frame.ids, frame.is_virtual))
        m = fu.set_up(view, [[-0.9, -0.2, 0.0], [-0.4, -0.3, 1.0]], frame.bounds, CHARGERS,
                      config=fu.UpkeepConfig(lost_after=0.5))
        assert sorted(m.ids.tolist()) == [2, 3]  # robots 0 and 1 are low on battery: they stay docked
        pacer, ticks = RealTimePacer(loop.config.dt), []

        def pace() -> None:
            ticks.append(1)
            if len(ticks) == 15:
                moving.stop()  # the fleet process of robots 2 and 3 dies mid-way
            pacer.wait()

        result = fu.run_maneuver(loop, m, pace, max_ticks=2000)
        assert not result.ok and m.state == "failed"
        assert "robot 2" in result.message and "robot 3" in result.message and "stopped reporting" in result.message
        assert "every robot stopped" in result.message
        frame = loop.tick()
        assert frame.stopped and any("stopped reporting" in a for a in frame.alerts)
        wait_until(lambda: np.all(stay.snapshot()["v"] == 0.0), 10, "the remaining robots at zero")
        assert np.allclose(stay.snapshot()["poses"], docks[[0, 1]], atol=1e-9)  # never left their strip
    finally:
        if loop is not None:
            loop.close()
        stay.stop()
        moving.stop()
