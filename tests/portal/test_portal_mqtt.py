"""The arena runner on networked robots: `swarmdeck robots --start docked --charge` (its own process) over a real
mosquitto is the arena's fleet; a job gets charged robots set up at its start poses through the console's loop and
barrier, runs on them as robots 0..N-1, and every robot is back on the chargers and still when it ends. A robot
of the fleet that never reports (id 3 here) is listed as missing and keeps the arena "not ready", but does not
stop the others from working."""
import json
import math
import subprocess
import sys

import numpy as np
import pytest
from mqtt_broker import wait_until
from portal_fixtures import skip_verification, wait_for_state

from swarmdeck.console.portal.runner import ArenaRunner, ArenaSettings
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.devices.chargers import ChargerLayout
from swarmdeck.devices.net.mqtt_config import parse_broker_url
from swarmdeck.devices.net.transport_mqtt import MqttTransport

pytestmark = [pytest.mark.mqtt, pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")]


def test_a_job_is_set_up_on_the_docked_mqtt_fleet_runs_and_the_robots_return(portal, mosquitto):
    fleet = subprocess.Popen([sys.executable, "-c", "import sys; from swarmdeck.console.cli import main; "
                              "sys.exit(main())", "robots", "--broker", mosquitto.url, "--robots", "3",
                              "--start", "docked", "--charge", "1", "--quiet"],
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    runner = ArenaRunner(portal.service, ArenaSettings(robots_via=mosquitto.url, fleet=4), poll_s=0.2)
    portal.service.arena = runner
    watcher = MqttTransport(parse_broker_url(mosquitto.url), ids=range(3)).start()
    layout = ChargerLayout()
    try:
        wait_until(lambda: len(watcher.latest_poses().ids) == 3, 60, "the fleet's poses")
        runner.start()
        table = wait_until(lambda: (t := runner.fleet_status())["docked"] == 3 and t, 30, "the docked fleet")
        assert [r["state"] for r in table["robots"]][3] == "missing" and not table["ready"]
        svc = portal.service
        goals = np.array([[-1.25, -0.5, 0.0], [-0.85, -0.55, 1.0]])
        jid = portal.submit("alice", robots=2, duration=1.5, initial_poses=goals.tolist()).json()["id"]
        skip_verification(portal, jid)  # verified (as the workers would leave it)
        with portal.client("alice") as c:
            job = wait_for_state(c, jid, ("done", "failed"), timeout=120)
        run = json.loads((svc.job_dir(jid) / "run.json").read_text())
        assert job["state"] == "done", (job["reason"], run)
        setup, back = run["setup"], run["return"]
        assert setup["ok"] and back["ok"] and setup["collisions"] == back["collisions"] == 0, run
        assert setup["max_position_error"] < 0.02 and setup["max_heading_error_deg"] < 5.0, setup
        assert sorted(back["robots"]) == sorted(setup["robots"]) and len(setup["robots"]) == 2
        with open_recording(svc.job_dir(jid) / "recording.mcap") as rec:
            frames = [f for _, f in rec.frames()]
            config = rec.config()["config"]
        assert config["source"].startswith("mqtt://") and config["fleet_ids"] == setup["robots"]
        first = frames[0]
        assert first.ids.tolist() == [0, 1] and frames[-1].params["safety_enabled"]
        assert np.all(np.hypot(*(first.poses[:, :2] - goals[:, :2]).T) < 0.02), (first.poses, goals)
        assert np.all(np.abs(np.angle(np.exp(1j * (first.poses[:, 2] - goals[:, 2])))) < math.radians(5))
        turned = np.abs(np.unwrap([f.poses[:, 2] for f in frames], axis=0)[-1] - first.poses[:, 2])
        assert np.all(turned > 0.2), turned  # ω = 0.5 rad/s for 1.5 s, through MQTT
        # every robot back on a charger (the fleet's own reports) and still
        a = wait_until(lambda: (p := watcher.latest_poses()) and len(p.ids) == 3 and p, what="fleet poses")
        assert (layout.docked_slot(a.poses) >= 0).all(), a.poses
        b = wait_until(lambda: (p := watcher.latest_poses()) and p.stamps.min() > a.stamps.max() + 0.3 and p,
                       what="fresh poses 0.3 s later")
        assert np.allclose(a.poses, b.poses, atol=1e-3), (a.poses, b.poses)
        status = runner.fleet_status()
        assert status["docked"] == 3 and status["assigned"] == {}
        assert [r["state"] for r in status["robots"]][3] == "missing" and not status["ready"]
    finally:
        watcher.close()
        runner.stop()
        fleet.terminate()
        fleet.wait(timeout=10)
