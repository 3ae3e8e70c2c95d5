"""The fleet in the console, in a real headless browser (Debian's Chromium through Playwright): the batteries
are shown (scene bars and the Batteries panel), the Set up button brings charged robots to the start poses of
a CSV file, the Return to chargers button docks them again. Assertions are on state (the loop's Frames, the
browser's scene tree and page text), never on timings."""
from __future__ import annotations

import os

import numpy as np
import pytest
from mqtt_broker import wait_until

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--no-sandbox", "--enable-unsafe-swiftshader", "--use-angle=swiftshader",
        "--disable-background-networking", "--disable-component-update"]

pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="Debian's chromium is not installed at /usr/bin/chromium "
                       "(scripts/test installs it)"),
]

GOALS = np.array([[-0.95, -0.45, 0.0], [-0.55, -0.5, 1.57]])


@pytest.fixture(scope="module")
def console():
    from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
    from swarmdeck.console.web.app import ConsoleApp
    from swarmdeck.devices import ArenaConfig
    from swarmdeck.devices.fleet import ChargerLayout
    from swarmdeck.devices.simulated_robots import SimulatedRobots

    sim = SimulatedRobots(4, ArenaConfig(seed=2), chargers=ChargerLayout(), start_docked=True,
                          charge=np.array([0.2, 0.9, 0.9, 0.9]))
    loop = ControlLoop(LoopConfig(n_robots=4, behaviour="rendezvous"), source=sim, sink=sim)
    loop.pause()  # nothing moves until a Fleet button is pressed
    app = ConsoleApp(loop, port=0).start()
    yield app
    app.close()


@pytest.fixture(scope="module")
def page(console):
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, headless=True, args=ARGS)
        pg = browser.new_page(viewport={"width": 1280, "height": 800})
        pg.goto(console.url)
        pg.wait_for_function("() => window.__viserSceneTree && window.__viserSceneTree.getState()['/battery']"
                             " !== undefined", timeout=60000)
        wait_until(lambda: len(console.server.get_clients()) > 0, 30)
        yield pg
        browser.close()


def test_batteries_are_shown(page, console) -> None:
    # four robots report: four grey tracks and four level bars in the scene
    page.wait_for_function("() => { const s = window.__viserSceneTree.getState()['/battery'];"
                           " return s && s.message.props.points.byteLength === 8 * 2 * 3 * 4; }", timeout=20000)
    page.get_by_text("4/4 report · 4 charging").wait_for(timeout=20000)
    assert page.get_by_text("🔵 charging").count() == 4


def test_set_up_button_brings_charged_robots_to_the_start_poses(page, console, tmp_path_factory) -> None:
    path = tmp_path_factory.mktemp("fleet") / "start.csv"
    path.write_text("x,y,theta\n" + "\n".join(",".join(str(v) for v in g) for g in GOALS) + "\n")
    # viser's label is not tied to its input: the input of the row holding that label
    box = page.locator("div.mantine-Flex-root", has=page.get_by_text("Start poses CSV", exact=True)).locator("input")
    box.fill(str(path))
    box.press("Enter")
    wait_until(lambda: console.gui.fleet.poses_path.value == str(path), 15)
    page.get_by_role("button", name="Set up", exact=True).click()
    wait_until(lambda: console.gui.fleet.maneuver is not None and console.gui.fleet.maneuver.state != "running", 180)
    m = console.gui.fleet.maneuver
    assert m.state == "done", m.message
    assert 0 not in m.ids.tolist()  # robot 0 (20 %) is not charged enough to be assigned
    frame = console.loop.latest
    rows = [int(np.flatnonzero(frame.ids == i)[0]) for i in m.ids]
    np.testing.assert_allclose(frame.poses[rows, :2], GOALS[:, :2], atol=0.02)
    page.get_by_text("set up: done in").last.wait_for(timeout=20000)  # the Fleet panel (and the status line)


def test_return_button_docks_every_robot(page, console) -> None:
    from swarmdeck.devices.fleet import ChargerLayout

    page.get_by_role("button", name="Return to chargers", exact=True).click()
    wait_until(lambda: console.gui.fleet.maneuver is not None and console.gui.fleet.maneuver.name == "return to chargers"
               and console.gui.fleet.maneuver.state != "running", 180)
    m = console.gui.fleet.maneuver
    assert m.state == "done", m.message
    frame = console.loop.latest
    assert (ChargerLayout().docked_slot(frame.poses) >= 0).all()
    wait_until(lambda: console.loop.latest.charging.all(), 15)
    page.get_by_text("4/4 robots docked · ready").wait_for(timeout=20000)
