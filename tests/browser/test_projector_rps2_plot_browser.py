"""A Robotarium 2.0 script that plots on its figure sees its drawing on the floor, end to end (issue 29: "anything
that you plot within the boundaries … will be projected onto the testbed"): the unmodified 2.0 example
``plotting/barriers_with_plotting.py`` runs sandboxed against a control loop (as the portal runs jobs), its ten
ring markers cross the trust boundary as annotations, the loop's Frames carry them, and the projector page in a real
browser (Debian's chromium) draws them on its annotations layer."""
from __future__ import annotations

import os
from pathlib import Path

import pytest
from mqtt_broker import wait_until

from swarmdeck.console.portal.runner import SandboxCommands
from swarmdeck.console.projector.server import ProjectorServer
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.plant import SandboxPlant
from swarmdeck.console.sandbox.run import run_sandboxed
from swarmdeck.core.annotations import POINT
from swarmdeck.core.bounds import DEFAULT_BOUNDS
from swarmdeck.tracking.projector import ProjectorCalibration, SyntheticProjector

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--no-sandbox", "--disable-background-networking", "--disable-component-update"]
SCRIPT = Path(__file__).resolve().parents[1] / "data" / "rps2_examples" / "master" / "plotting" / "barriers_with_plotting.py"
PROJ = SyntheticProjector(tilt=0.15, roll=0.03)
pytestmark = [pytest.mark.browser, pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium"),
              pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")]


def test_an_rps2_scripts_plot_reaches_the_projector_page():
    from playwright.sync_api import sync_playwright

    frames = []
    loop = ControlLoop(LoopConfig(n_robots=10, seed=3))
    projector = ProjectorServer(DEFAULT_BOUNDS, ProjectorCalibration(PROJ.homography(), PROJ.size, DEFAULT_BOUNDS),
                                port=0).start()
    loop.subscribe(projector.offer)
    loop.subscribe(frames.append)

    def make_plant(n, initial):
        commands = SandboxCommands()
        loop.use_behaviour(commands)
        loop.pause()
        loop.tick()
        loop.run()
        return SandboxPlant.on_loop(loop, commands, 0.5, None)

    try:
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
            try:
                page = browser.new_page(viewport={"width": PROJ.width, "height": PROJ.height})
                page.goto(projector.url)  # opened before the job starts, as on the projector's screen
                out = run_sandboxed(SCRIPT, make_plant, n_robots=10, duration=0.5, rps=True, rps_generation=2)
                assert out.ok or out.ended_by == "duration", out.error
                drawn = [f.annotations for f in frames if f.annotations is not None]
                assert drawn and drawn[-1].kinds.tolist() == [POINT] * 10  # one ring marker per robot, as the script drew
                wait_until(lambda: page.evaluate("window.swarmdeckProjector.annotationsDrawn") == 10, 30.0,
                           "the ten rings on the projector page")
                assert "annotations" in page.evaluate("window.swarmdeckProjector.layersDrawn")
            finally:
                browser.close()
    finally:
        projector.close()
        loop.close()
