"""`swarmdeck run SCRIPT --robots-via mqtt://…`: an experiment script on networked robots, opened by the one
robots factory and driven by the Arena through the same ports and safety pipeline as the simulation."""
from __future__ import annotations

import json
import subprocess
import sys

import pytest
from mqtt_broker import wait_until

from swarmdeck.console.cli import main
from swarmdeck.devices.net.mqtt_config import parse_broker_url
from swarmdeck.devices.net.transport_mqtt import MqttTransport

pytestmark = pytest.mark.mqtt

SCRIPT = """
import numpy as np
from swarmdeck.devices import Arena

arena = Arena(3, duration=0.5)
start = arena.positions()
while True:
    arena.set_goals(start + np.array([0.05, 0.0]))
    arena.step()
"""


def test_a_script_runs_on_the_mqtt_robots(mosquitto, tmp_path, capsys):
    script = tmp_path / "exp.py"
    script.write_text(SCRIPT)
    fleet = subprocess.Popen([sys.executable, "-c", "import sys; from swarmdeck.console.cli import main; sys.exit(main())",
                              "robots", "--broker", mosquitto.url, "--robots", "3", "--seed", "5", "--quiet"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        # the fleet's process is up before the run looks for it (the run waits 5 s for the first poses; a loaded
        # machine can take longer than that just to start a Python process)
        watcher = MqttTransport(parse_broker_url(mosquitto.url), ids=range(3)).start()
        try:
            wait_until(lambda: len(watcher.latest_poses().ids) == 3, 60, "the fleet's poses")
        finally:
            watcher.close()
        code = main(["run", str(script), "--robots-via", mosquitto.url, "--robots", "3", "--json"])
    finally:
        fleet.terminate()
        fleet.communicate(timeout=10)
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["error"] is None
    report = out["reports"][0]
    assert report["n_robots"] == 3 and report["time"] >= 0.5 and report["safety"]["enabled"]
    assert report["safety"]["calls"] >= 1 and report["safety"]["failures"] == 0


def test_robots_via_needs_robots_and_names_a_silent_broker(mosquitto, tmp_path, capsys):
    script = tmp_path / "exp.py"
    script.write_text(SCRIPT)
    assert main(["run", str(script), "--robots-via", mosquitto.url]) == 2
    assert "--robots-via needs --robots N" in capsys.readouterr().err
    assert main(["run", str(script), "--robots-via", mosquitto.url, "--robots", "3", "--sandbox"]) == 2
    assert "--robots-via does not combine with --sandbox" in capsys.readouterr().err
