"""The console's scene in a real browser (Debian's chromium) has the issue-28 layers — the robots' sensor rays,
the network links and the floor's obstacles — as "Layers" checkboxes, and switching a layer off hides its scene
node in the browser. Assertions are on the browser's viser scene tree and GUI, never on frame rates."""
from __future__ import annotations

import os
import time

import pytest

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--no-sandbox", "--enable-unsafe-swiftshader", "--use-angle=swiftshader",
        "--disable-background-networking", "--disable-component-update"]
pytestmark = [pytest.mark.browser,
              pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium at /usr/bin/chromium")]

NODES = {"sensors": "/sensors/rays", "network": "/network", "obstacles": "/obstacles"}
VISIBLE = """(name) => {
  const s = window.__viserSceneTree && window.__viserSceneTree.getState()[name];
  return s ? s.visibility : null;
}"""


def test_the_console_switches_the_sensors_network_and_obstacles_layers():
    from playwright.sync_api import sync_playwright

    from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
    from swarmdeck.console.web.app import ConsoleApp
    from swarmdeck.core.obstacles import Obstacles

    wall = Obstacles([[[-0.6, 0.5], [0.6, 0.5]]])
    app = ConsoleApp(ControlLoop(LoopConfig(seed=11, n_robots=4, sensors=True, obstacles=wall)), port=0).start()
    try:
        app.loop.run()
        deadline = time.monotonic() + 60
        while (app.loop.latest is None or app.loop.latest.sensors is None) and time.monotonic() < deadline:
            time.sleep(0.02)
        assert app.loop.latest.sensors is not None
        assert set(NODES) <= set(app.gui.layers)  # the "Layers" folder's checkboxes
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, headless=True, args=ARGS)
            try:
                page = browser.new_page(viewport={"width": 1280, "height": 800})
                page.goto(app.url)
                for node in NODES.values():
                    page.wait_for_function(f"() => ({VISIBLE})({node!r}) === true", timeout=60_000)
                for layer, node in NODES.items():
                    app.scene.set_layer(layer, False)  # what the checkbox calls (ConsoleGui)
                    page.wait_for_function(f"() => ({VISIBLE})({node!r}) === false", timeout=30_000)
                    app.scene.set_layer(layer, True)
                    page.wait_for_function(f"() => ({VISIBLE})({node!r}) === true", timeout=30_000)
            finally:
                browser.close()
    finally:
        app.close()
