"""The console in a real headless browser (Debian's Chromium through Playwright; REFERENCE.md §8).

Assertions are on state (the browser's scene tree, the loop's Frames), never on frame rates.
A screenshot is kept in ``test-artifacts/console.png``.
"""
from __future__ import annotations

import math
import os
import time
from pathlib import Path

import numpy as np
import pytest

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--no-sandbox", "--enable-unsafe-swiftshader", "--use-angle=swiftshader",
        "--disable-background-networking", "--disable-component-update"]
VIEW = {"width": 1280, "height": 800}
ARTIFACTS = Path(__file__).resolve().parents[2] / "test-artifacts"

pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="Debian's chromium is not installed at /usr/bin/chromium "
                       "(scripts/test installs it)"),
]

POSITIONS_MATCH = """([exp, tol]) => {
  const s = window.__viserSceneTree && window.__viserSceneTree.getState()['/robots'];
  if (!s) return false;
  const p = s.message.props.batched_positions;
  const a = new Float32Array(p.buffer, p.byteOffset, p.byteLength / 4);
  if (a.length !== exp.length * 3) return false;
  for (let i = 0; i < exp.length; i++) {
    if (Math.abs(a[3 * i] - exp[i][0]) > tol || Math.abs(a[3 * i + 1] - exp[i][1]) > tol) return false;
  }
  return true;
}"""


def wait_until(cond, timeout: float = 15.0) -> None:
    """Poll a condition on server-side state (bounded; not a sleep for correctness)."""
    deadline = time.monotonic() + timeout
    while not cond():
        if time.monotonic() > deadline:
            raise AssertionError("condition not reached within the timeout")
        time.sleep(0.02)


@pytest.fixture(scope="module")
def console():
    from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
    from swarmdeck.console.web.app import ConsoleApp

    app = ConsoleApp(ControlLoop(LoopConfig(seed=11, n_robots=8)), port=0).start()
    yield app
    app.close()


@pytest.fixture(scope="module")
def page(console):
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, headless=True, args=ARGS)
        pg = browser.new_page(viewport=VIEW)
        pg.goto(console.url)
        pg.wait_for_function("() => window.__viserSceneTree && window.__viserSceneTree.getState()['/robots']"
                             " !== undefined && window.__viserSceneTree.getState()['/voronoi'] !== undefined",
                             timeout=60000)
        wait_until(lambda: len(console.server.get_clients()) > 0, 30)
        yield pg
        browser.close()


def running(console) -> None:
    console.loop.release()
    console.loop.run()


def test_page_holds_robots_and_voronoi(page, console) -> None:
    names = page.evaluate("() => Object.keys(window.__viserSceneTree.getState())")
    for name in ("/robots", "/voronoi", "/density", "/centroids", "/barrier", "/labels/r0", "/arena/boundary"):
        assert name in names
    assert page.get_by_role("button", name="EMERGENCY STOP", exact=True).is_visible()


def test_robot_positions_follow_the_simulation(page, console) -> None:
    loop = console.loop
    running(console)
    loop.pause()
    wait_until(lambda: loop.latest.run_state == "paused")
    before = loop.latest.poses[:, :2].tolist()
    page.wait_for_function(POSITIONS_MATCH, arg=[before, 1e-4], polling="raf", timeout=20000)
    loop.step(30)
    wait_until(lambda: loop.pending_steps == 0)
    settled = loop.latest.tick
    wait_until(lambda: loop.latest.tick >= settled + 2)  # a paused frame sensed after the last step
    after = loop.latest.poses[:, :2].tolist()
    assert np.abs(np.subtract(after, before)).max() > 5e-3  # the robots moved
    page.wait_for_function(POSITIONS_MATCH, arg=[after, 1e-4], polling="raf", timeout=20000)


def test_clicking_on_the_arena_adds_a_bump(page, console) -> None:
    running(console)
    cam = console.server.initial_camera
    look, pos, fov = np.asarray(cam.look_at), np.asarray(cam.position), float(cam.fov)
    m_per_px = 2 * (pos[2] - look[2]) * math.tan(fov / 2) / VIEW["height"]
    target = np.array([-0.8, 0.4])
    px = VIEW["width"] / 2 + (target[0] - look[0]) / m_per_px
    py = VIEW["height"] / 2 - (target[1] - look[1]) / m_per_px
    before = {b.id for b in console.loop.bumps.live()}
    page.mouse.click(px, py)
    wait_until(lambda: len(console.loop.bumps.live()) > len(before))
    new = [b for b in console.loop.bumps.live() if b.id not in before][0]
    assert np.linalg.norm(np.subtract(new.mu, target)) < 0.05
    page.wait_for_function(f"() => window.__viserSceneTree.getState()['/bumps/b{new.id}'] !== undefined",
                           timeout=20000)
    wait_until(lambda: console.loop.latest.density is not None and any(
        np.linalg.norm(console.loop.latest.density.mu - target, axis=1) < 0.05))


def test_emergency_stop_button_stops_the_robots(page, console) -> None:
    loop = console.loop
    running(console)
    wait_until(lambda: loop.latest.run_state == "running" and not loop.latest.stopped)
    page.get_by_role("button", name="EMERGENCY STOP", exact=True).click()
    wait_until(lambda: loop.latest.run_state == "estop")
    first = loop.latest
    assert first.stopped
    wait_until(lambda: loop.latest.tick >= first.tick + 3)
    assert loop.latest.stopped and loop.latest.run_state == "estop"
    np.testing.assert_allclose(loop.latest.poses, first.poses, atol=1e-12)
    page.get_by_text("EMERGENCY STOP", exact=False).first.wait_for()


def test_space_bar_is_an_emergency_stop(page, console) -> None:
    loop = console.loop
    running(console)
    wait_until(lambda: loop.latest.run_state == "running")
    page.get_by_text("RUNNING").first.click()  # focus the page without clicking the arena
    page.keyboard.press("Space")
    wait_until(lambda: loop.latest.run_state == "estop")


def test_a_late_tab_sees_the_current_state(page, console) -> None:
    loop = console.loop
    running(console)
    loop.pause()
    wait_until(lambda: loop.latest.run_state == "paused")
    settled = loop.latest.tick
    wait_until(lambda: loop.latest.tick >= settled + 2)
    now = loop.latest.poses[:, :2].tolist()
    late = page.context.browser.new_page(viewport=VIEW)
    try:
        late.goto(console.url)
        late.wait_for_function(POSITIONS_MATCH, arg=[now, 1e-4], polling="raf", timeout=60000)
        page.wait_for_function(POSITIONS_MATCH, arg=[now, 1e-4], polling="raf", timeout=20000)
    finally:
        late.close()


def test_screenshot(page, console) -> None:
    running(console)
    if not console.loop.bumps.live():
        console.loop.add_bump((1.0, -0.4))
    wait_until(lambda: console.loop.latest.tick > 0)
    page.mouse.move(300, 400)
    page.mouse.down()
    page.mouse.move(420, 330, steps=5)  # orbit the view away…
    page.mouse.up()
    page.get_by_role("button", name="Top view", exact=True).click()  # …and back to the top view
    client = next(iter(console.server.get_clients().values()))
    top = np.asarray(console.server.initial_camera.position)
    wait_until(lambda: np.allclose(client.camera.position, top, atol=1e-3)
               and np.allclose(client.camera.look_at, console.server.initial_camera.look_at, atol=1e-3))
    page.wait_for_timeout(1500)  # let a few updates render for the picture (not for any assertion)
    ARTIFACTS.mkdir(exist_ok=True)
    out = ARTIFACTS / "console.png"
    page.screenshot(path=str(out))
    assert out.stat().st_size > 10_000
