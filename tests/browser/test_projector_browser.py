"""The projector page in a real browser (Debian's chromium) against the real projector server on loopback, fed by
a real control loop: it draws the newest Frame warped onto the floor, in two pages at once, from before the loop
starts to after the server stops (and when it comes back); without a homography it says so on the floor; blackout goes black; and the
whole chain — calibrate the synthetic projector, show the page's pixels through it, look with the synthetic
camera — puts the projected density where the density is."""
from __future__ import annotations

import os

import cv2
import numpy as np
import pytest
from mqtt_broker import wait_until

from swarmdeck.console.picture.heat import heatmap
from swarmdeck.console.projector.server import ProjectorServer
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.core.bounds import DEFAULT_BOUNDS
from swarmdeck.tracking.calibration import CameraCalibration
from swarmdeck.tracking.projector import (
    ProjectorCalibration,
    SyntheticProjector,
    find_pattern,
    fit_projector,
    marker_pattern,
)
from swarmdeck.tracking.synthetic import SyntheticCameraConfig, SyntheticRenderer

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--no-sandbox", "--disable-background-networking", "--disable-component-update"]
pytestmark = [pytest.mark.browser, pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium")]
PROJ = SyntheticProjector(tilt=0.15, roll=0.03)
STATE = "window.swarmdeckProjector"


@pytest.fixture
def browser():
    from playwright.sync_api import sync_playwright

    with sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        try:
            yield b
        finally:
            b.close()


@pytest.fixture
def loop():
    lp = ControlLoop(LoopConfig(n_robots=12, seed=4))
    try:
        yield lp
    finally:
        lp.close()


def _serve(loop, calibration):
    srv = ProjectorServer(loop.config.bounds, calibration, port=0).start()
    loop.subscribe(srv.offer)
    return srv


def _page(browser, srv):
    page = browser.new_page(viewport={"width": PROJ.width, "height": PROJ.height})
    page.goto(srv.url)
    return page


def _state(page):
    return page.evaluate(f"(() => {{ const s = {STATE}; return {{frames: s.frames, seq: s.seq, message: s.message, "
                         f"connected: s.connected, layers: s.layersDrawn, dropped: s.dropped}}; }})()")


def test_two_pages_opened_before_the_loop_starts_draw_its_newest_frames_and_survive_the_server_stopping(browser, loop):
    srv = _serve(loop, ProjectorCalibration(PROJ.homography(), PROJ.size, DEFAULT_BOUNDS))
    try:
        pages = [_page(browser, srv), _page(browser, srv)]
        for page in pages:  # no Frame yet: connected, nothing drawn, no error
            wait_until(lambda page=page: _state(page)["connected"], 30.0)
            assert _state(page)["frames"] == 0
        for _ in range(5):
            loop.tick()
        for page in pages:
            wait_until(lambda page=page: _state(page)["seq"] == 5, 30.0)
            st = _state(page)
            assert st["message"] == "" and {"density", "cells", "halos"} <= set(st["layers"])
        assert srv.state()["pages"] == 2
    finally:
        srv.close()
    for page in pages:  # the server went away: the pages go black and say so
        wait_until(lambda page=page: not _state(page)["connected"], 30.0)
        assert "waiting for the console" in _state(page)["message"]
    # the console comes back on the same port: the pages draw its frames from its first one (its seq restarts)
    again = ProjectorServer(loop.config.bounds, ProjectorCalibration(PROJ.homography(), PROJ.size, DEFAULT_BOUNDS),
                            port=srv.port).start()
    try:
        loop.subscribe(again.offer)
        loop.tick()
        for page in pages:
            wait_until(lambda page=page: _state(page)["connected"] and _state(page)["seq"] == 1, 30.0)
            assert _state(page)["message"] == ""
    finally:
        again.close()


def test_without_a_homography_the_floor_says_to_calibrate(browser, loop):
    srv = _serve(loop, None)
    try:
        page = _page(browser, srv)
        loop.tick()
        wait_until(lambda: "no homography" in _state(page)["message"], 30.0)
        assert _state(page)["message"] == "no homography — run swarmdeck calibrate projector"
        shot = cv2.imdecode(np.frombuffer(page.screenshot(), np.uint8), cv2.IMREAD_GRAYSCALE)
        assert shot[PROJ.height // 3: 2 * PROJ.height // 3].max() > 200  # the words are on the screen
    finally:
        srv.close()


def test_layers_and_blackout_from_the_settings(browser, loop):
    srv = _serve(loop, ProjectorCalibration(PROJ.homography(), PROJ.size, DEFAULT_BOUNDS))
    try:
        page = _page(browser, srv)
        loop.tick()
        wait_until(lambda: "cells" in _state(page)["layers"], 30.0)
        srv.set(cells=False, halos=False)
        wait_until(lambda: not {"cells", "halos"} & set(_state(page)["layers"]), 30.0)
        assert "density" in _state(page)["layers"]
        srv.set(blackout=True)
        loop.tick()
        wait_until(lambda: _state(page)["layers"] == [], 30.0)
        shot = cv2.imdecode(np.frombuffer(page.screenshot(), np.uint8), cv2.IMREAD_GRAYSCALE)
        assert shot.max() < 8  # black
    finally:
        srv.close()


def _sample(image, r, pts):
    px = np.round(r.camera.project(np.column_stack([pts, np.zeros(len(pts))]))).astype(int)
    return image[px[:, 1], px[:, 0]].astype(float)


def test_calibrated_projection_of_the_density_lands_where_the_density_is(browser, loop):
    r = SyntheticRenderer(SyntheticCameraConfig())
    cal = CameraCalibration.from_camera(r.camera)
    floor_h = np.linalg.inv(cal.camera_matrix @ r.camera.plane_homography(0.0))
    pattern = marker_pattern(PROJ.size)  # calibrate: project → see → detect → fit
    seen = find_pattern(r.render([], np.zeros((0, 3)), projection=(pattern.image, PROJ.homography())).image[..., 1],
                        pattern, floor_h / floor_h[2, 2], cal.undistort)
    fit = fit_projector(seen.floor_corners, seen.pattern_corners, DEFAULT_BOUNDS, PROJ.size)
    assert fit.ok and fit.H is not None, fit.reason
    srv = _serve(loop, ProjectorCalibration(fit.H, PROJ.size, DEFAULT_BOUNDS, fit.rms_mm, len(seen.ids)))
    try:
        srv.set(cells=False, centroids=False, halos=False, goals=False)
        page = _page(browser, srv)
        frame = loop.tick()
        wait_until(lambda: _state(page)["seq"] == 1 and "density" in _state(page)["layers"], 30.0)
        shot = cv2.cvtColor(cv2.imdecode(np.frombuffer(page.screenshot(), np.uint8), cv2.IMREAD_COLOR),
                            cv2.COLOR_BGR2RGB)
    finally:
        srv.close()
    # the projector shows the page's pixels; the camera sees them on the floor
    dark = r.render([], np.zeros((0, 3)), rng=np.random.default_rng(1)).image
    lit = r.render([], np.zeros((0, 3)), rng=np.random.default_rng(1), projection=(shot, PROJ.homography())).image
    k = r.config.projection_strength
    xs, ys = np.meshgrid(np.linspace(-1.45, 1.45, 30), np.linspace(-0.85, 0.85, 18))
    pts = np.column_stack([xs.ravel(), ys.ravel()])
    seen_light = ((_sample(lit, r, pts) / np.maximum(_sample(dark, r, pts), 1.0)) - (1 - k)) / k * 255.0
    heat = heatmap(frame.density, DEFAULT_BOUNDS, 50.0).astype(float)
    rows = np.clip(((DEFAULT_BOUNDS[3] - pts[:, 1]) * 50.0).astype(int), 0, heat.shape[0] - 1)
    cols = np.clip(((pts[:, 0] - DEFAULT_BOUNDS[0]) * 50.0).astype(int), 0, heat.shape[1] - 1)
    want = heat[rows, cols]
    err = np.abs(seen_light - want).mean(axis=1)
    assert np.median(err) < 25.0, np.median(err)
    # where the density is: the darkest (highest φ) light the camera sees sits on the density's peak
    hot = (765.0 - seen_light.sum(axis=1)).clip(0)
    hot_want = (765.0 - want.sum(axis=1)).clip(0)
    centre_seen = (pts * hot[:, None]).sum(0) / hot.sum()
    centre_want = (pts * hot_want[:, None]).sum(0) / hot_want.sum()
    assert np.linalg.norm(centre_seen - centre_want) < 0.03, (centre_seen, centre_want)


def test_a_slow_page_drops_layers_instead_of_lagging(browser, loop):
    srv = _serve(loop, ProjectorCalibration(PROJ.homography(), PROJ.size, DEFAULT_BOUNDS))
    try:
        srv.set(safety=True)
        page = browser.new_page(viewport={"width": PROJ.width, "height": PROJ.height})
        # every arc costs 3 ms: the safety discs and halos of 12 robots put a frame far over the 20 ms budget
        page.add_init_script("""(() => { const arc = CanvasRenderingContext2D.prototype.arc;
            CanvasRenderingContext2D.prototype.arc = function (...a) {
              const t = performance.now(); while (performance.now() - t < 3) {} return arc.apply(this, a); }; })()""")
        page.goto(srv.url)
        for k in range(1, 40):
            loop.tick()
            if k % 4 == 0:
                wait_until(lambda k=k: _state(page)["seq"] == k, 30.0)
        st = _state(page)
        assert st["dropped"][:2] == ["safety", "halos"], st
        assert "density" in st["layers"] and "safety" not in st["layers"] and "halos" not in st["layers"]
    finally:
        srv.close()
