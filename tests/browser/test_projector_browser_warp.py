"""The projector page warps every vertex itself (issue 29's frame-rate work): what it draws lands where the
floor → projector homography says, in a real browser (Debian's chromium) against the real projector server on
loopback. Markers drawn at known floor points are found in the page's screenshot at H·p (their pixels'
centroid), a circle on the floor becomes the exact conic H makes of it (an ellipse: every pixel of its outline
maps back to the circle, and every point of the circle is drawn), and the arena's outline is H's quadrilateral."""
from __future__ import annotations

import dataclasses
import os

import cv2
import numpy as np
import pytest
from mqtt_broker import wait_until

from swarmdeck.console.projector.server import ProjectorServer
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.core.annotations import CIRCLE, POINT, Annotations
from swarmdeck.core.bounds import DEFAULT_BOUNDS
from swarmdeck.tracking.projector import ProjectorCalibration, SyntheticProjector

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--no-sandbox", "--disable-background-networking", "--disable-component-update"]
pytestmark = [pytest.mark.browser, pytest.mark.skipif(not os.path.exists(CHROMIUM), reason="needs Debian's chromium")]
PROJ = SyntheticProjector(tilt=0.25, roll=0.05)  # a strong keystone: a CSS-free warp must get the perspective right
STATE = "window.swarmdeckProjector"
#: marker centres on the floor, m, and their colours (pure, so their pixels are told apart from everything else)
MARKS = np.array([[-1.3, 0.75], [1.35, 0.7], [-1.25, -0.8], [1.3, -0.75], [0.05, 0.02]])
MARK_COLOURS = np.array([[255, 0, 0], [0, 255, 0], [0, 0, 255], [255, 0, 255], [0, 255, 255]])
MARK_RADIUS = 0.03
CIRCLE_CENTRE, CIRCLE_RADIUS, CIRCLE_COLOUR = np.array([0.3, -0.1]), 0.55, np.array([255, 255, 0])


def _project(H: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """Floor m (K, 2) → projector px (K, 2), pixel centres at integers."""
    p = np.column_stack([xy, np.ones(len(xy))]) @ H.T
    return p[:, :2] / p[:, 2:]


def _annotations() -> Annotations:
    kinds = [POINT] * len(MARKS) + [CIRCLE]
    colours = np.vstack([MARK_COLOURS, CIRCLE_COLOUR[None]])
    return Annotations(kinds=np.array(kinds, dtype=np.uint8), offsets=np.arange(len(kinds) + 1),
                       vertices=np.vstack([MARKS, CIRCLE_CENTRE[None]]),
                       sizes=np.array([MARK_RADIUS] * len(MARKS) + [CIRCLE_RADIUS]),
                       colors=np.column_stack([colours, np.full(len(kinds), 255)]).astype(np.uint8),
                       filled=np.zeros(len(kinds), dtype=bool), texts=("",) * len(kinds))


@pytest.fixture(scope="module")
def shot():
    """The page's screenshot (RGB) of one Frame carrying the markers and the circle, every other layer off."""
    from playwright.sync_api import sync_playwright

    H = PROJ.homography()
    loop = ControlLoop(LoopConfig(n_robots=4, seed=2))
    srv = ProjectorServer(loop.config.bounds, ProjectorCalibration(H, PROJ.size, DEFAULT_BOUNDS), port=0).start()
    try:
        srv.set(density=False, cells=False, centroids=False, goals=False, halos=False, safety=False, graph=False)
        frame = dataclasses.replace(loop.tick(), annotations=_annotations())
        with sync_playwright() as pw:
            browser = pw.chromium.launch(executable_path=CHROMIUM, args=ARGS)
            try:
                page = browser.new_page(viewport={"width": PROJ.width, "height": PROJ.height})
                page.goto(srv.url)
                srv.offer(frame)
                wait_until(lambda: page.evaluate(f"{STATE}.annotationsDrawn") == len(MARKS) + 1, 30.0)
                image = cv2.cvtColor(cv2.imdecode(np.frombuffer(page.screenshot(), np.uint8), cv2.IMREAD_COLOR),
                                     cv2.COLOR_BGR2RGB)
                js = page.evaluate(f"{MARKS.tolist()}.map(([x, y]) => {STATE}.project(x, y))")
            finally:
                browser.close()
    finally:
        srv.close()
        loop.close()
    return {"image": image, "H": H, "js": np.asarray(js)}


def _mask(image: np.ndarray, colour: np.ndarray) -> np.ndarray:
    """Pixels within 60 of ``colour`` in every channel (the fill, not its anti-aliased rim), (rows, cols) bool."""
    return np.all(np.abs(image.astype(int) - colour) < 60, axis=2)


def test_markers_land_where_the_homography_puts_them(shot):
    want = _project(shot["H"], MARKS)
    np.testing.assert_allclose(shot["js"], want, atol=1e-6)  # the page's own homography is the calibration's
    for c, colour, (wx, wy) in zip(MARKS, MARK_COLOURS, want, strict=True):
        rows, cols = np.nonzero(_mask(shot["image"], colour))
        assert len(rows) > 20, f"marker {colour} not drawn (expected at {wx:.1f}, {wy:.1f} px)"
        centre = np.array([cols.mean(), rows.mean()])
        assert np.hypot(*(centre - (wx, wy))) < 0.75, (colour.tolist(), centre, (wx, wy))
        # its size is the homography's too: the disc's area ≈ π r² × |det J| at its centre
        e = 1e-4
        J = (_project(shot["H"], np.array([c + (e, 0), c + (0, e)])) - _project(shot["H"], c[None])) / e
        area = np.pi * MARK_RADIUS**2 * abs(np.linalg.det(J))
        assert 0.75 * area < len(rows) < 1.25 * area, (len(rows), area)


def test_a_circle_on_the_floor_is_the_ellipse_the_homography_makes_of_it(shot):
    H, image = shot["H"], shot["image"]
    ring = _mask(image, CIRCLE_COLOUR)
    rows, cols = np.nonzero(ring)
    assert len(rows) > 500
    # every pixel of the outline maps back onto the circle (within the line's half width and a pixel)
    back = _project(np.linalg.inv(H), np.column_stack([cols, rows]).astype(float))
    r = np.hypot(*(back - CIRCLE_CENTRE).T)
    e, c = 1e-4, CIRCLE_CENTRE
    J = (_project(H, np.array([c + (e, 0), c + (0, e)])) - _project(H, c[None])) / e
    tol = 0.005 + 1.5 / np.sqrt(abs(np.linalg.det(J)))  # half the page's 1 cm line + 1.5 px, m
    assert np.abs(r - CIRCLE_RADIUS).max() < tol, np.abs(r - CIRCLE_RADIUS).max()
    # and every point of the circle is drawn (a pixel of the outline within 1.5 px of its image)
    a = np.linspace(0, 2 * np.pi, 90, endpoint=False)
    want = _project(H, CIRCLE_CENTRE + CIRCLE_RADIUS * np.column_stack([np.cos(a), np.sin(a)]))
    dist = cv2.distanceTransform((~ring).astype(np.uint8), cv2.DIST_L2, 5)
    at = dist[np.round(want[:, 1]).astype(int), np.round(want[:, 0]).astype(int)]
    assert at.max() <= 1.5, at.max()


def test_the_arena_outline_is_the_homographys_quadrilateral(shot):
    H, image = shot["H"], shot["image"]
    x0, x1, y0, y1 = DEFAULT_BOUNDS
    lit = image.max(axis=2) > 20  # the boundary's grey
    dist = cv2.distanceTransform((~lit).astype(np.uint8), cv2.DIST_L2, 5)
    t = np.linspace(0, 1, 40)
    edges = np.vstack([np.column_stack([x0 + (x1 - x0) * t, np.full_like(t, y)]) for y in (y0, y1)] +
                      [np.column_stack([np.full_like(t, x), y0 + (y1 - y0) * t]) for x in (x0, x1)])
    want = _project(H, edges)
    inside = (want[:, 0] >= 0) & (want[:, 0] < PROJ.width - 0.5) & (want[:, 1] >= 0) & (want[:, 1] < PROJ.height - 0.5)
    assert inside.mean() > 0.9
    at = dist[np.round(want[inside, 1]).astype(int), np.round(want[inside, 0]).astype(int)]
    assert at.max() <= 1.5, at.max()
