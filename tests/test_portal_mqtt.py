"""The arena runner on networked robots: a job runs on `swarmdeck robots` (its own process) over a real mosquitto,
through the same loop, barrier and recorder, and the robots are stopped when it ends; a job with initial poses
first drives the robots there."""
import json
import subprocess
import sys

import numpy as np
import pytest
from mqtt_broker import mosquitto, wait_until  # noqa: F401
from portal_fixtures import portal, wait_for_state  # noqa: F401

from swarmdeck.console.jobs.confinement import probe
from swarmdeck.console.portal.runner import ArenaRunner, ArenaSettings
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.devices.net.mqtt_config import parse_broker_url
from swarmdeck.devices.net.transport_mqtt import MqttTransport

pytestmark = [pytest.mark.mqtt, pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")]


def test_a_job_runs_on_the_mqtt_fleet_and_leaves_the_robots_stopped(portal, mosquitto):
    fleet = subprocess.Popen([sys.executable, "-c", "import sys; from swarmdeck.console.cli import main; "
                              "sys.exit(main())", "robots", "--broker", mosquitto.url, "--robots", "3", "--seed", "5",
                              "--quiet"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    runner = ArenaRunner(portal.service, ArenaSettings(robots_via=mosquitto.url, fleet=3), poll_s=0.2)
    portal.service.arena = runner
    runner.start()
    watcher = MqttTransport(parse_broker_url(mosquitto.url), ids=range(3)).start()
    try:
        wait_until(lambda: len(watcher.latest_poses().ids) == 3, 60, "the fleet's poses")
        svc = portal.service
        jid = portal.submit("alice", robots=2, duration=1.5).json()["id"]
        with svc.db.transaction() as tx:  # verified (as the workers would leave it)
            svc.db.transition(tx, jid, "verifying")
            svc.db.transition(tx, jid, "approved", verdict="accepted")
            svc.db.transition(tx, jid, "waiting")
        svc.notify()
        with portal.client("alice") as c:
            job = wait_for_state(c, jid, ("done", "failed"), timeout=60)
        assert job["state"] == "done", (job["reason"], (svc.job_dir(jid) / "run.json").read_text())
        with open_recording(svc.job_dir(jid) / "recording.mcap") as rec:
            frames = [f for _, f in rec.frames()]
            assert rec.config()["config"]["source"].startswith("mqtt://")
        assert frames[-1].ids.tolist() == [0, 1] and frames[-1].params["safety_enabled"]
        turned = np.abs(np.unwrap([f.poses[:, 2] for f in frames], axis=0)[-1] - frames[0].poses[:, 2])
        assert np.all(turned > 0.2), turned  # ω = 0.5 rad/s for 1.5 s, through MQTT
        # stopped when the job ended: the poses the fleet reports no longer change (its own firmware timeout
        # would let a robot run on for 0.5 s)
        a = wait_until(lambda: (p := watcher.latest_poses()) and len(p.ids) == 3 and p, what="fleet poses")
        b = wait_until(lambda: (p := watcher.latest_poses()) and p.stamps.min() > a.stamps.max() + 0.3 and p,
                       what="fresh poses 0.3 s later")
        assert np.allclose(a.poses, b.poses, atol=1e-3), (a.poses, b.poses)
        # a job with initial poses: the robots first drive there (barrier on), then the script starts
        start = b.poses[:2].copy()
        goals = start[:, :2] - 0.15 * np.sign(start[:, :2])  # 0.15 m towards the middle, separation kept
        initial = [[float(x), float(y), 0.0] for x, y in goals]
        jid = portal.submit("alice", robots=2, duration=0.5, initial_poses=initial).json()["id"]
        with svc.db.transaction() as tx:
            svc.db.transition(tx, jid, "verifying")
            svc.db.transition(tx, jid, "approved", verdict="accepted")
            svc.db.transition(tx, jid, "waiting")
        svc.notify()
        with portal.client("alice") as c:
            job = wait_for_state(c, jid, ("done", "failed"), timeout=90)
        run = json.loads((svc.job_dir(jid) / "run.json").read_text())
        assert job["state"] == "done" and run["note"] == "robots at their initial positions", (job, run)
        with open_recording(svc.job_dir(jid) / "recording.mcap") as rec:
            first = next(f for _, f in rec.frames())
        assert np.all(np.hypot(*(first.poses[:, :2] - goals).T) < 0.06), (first.poses, goals)
    finally:
        watcher.close()
        runner.stop()
        fleet.terminate()
        fleet.wait(timeout=10)
