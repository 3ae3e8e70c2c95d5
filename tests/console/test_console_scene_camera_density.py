"""Camera mode: the density heat map is drawn over the camera picture, translucent (scene state)."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import viser

from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.console.web.scene import ArenaScene

BOUNDS = (-1.6, 1.6, -1.0, 1.0)


def _camera(ref: str):
    """An overhead picture: a dark floor with a bright stripe (what the image provider returns)."""
    img = np.full((100, 160, 3), 40, dtype=np.uint8)
    img[40:60] = 230
    return img, BOUNDS


@pytest.fixture(scope="module")
def server():
    s = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield s
    s.stop()


def _frames(n: int = 3):
    loop = ControlLoop(LoopConfig(seed=3, n_robots=5))
    return [dataclasses.replace(loop.tick(), image_ref=f"camera:{i}") for i in range(n)]


def test_density_lies_over_the_camera_picture_and_lets_it_through(server) -> None:
    server.scene.reset()
    scene = ArenaScene(server, BOUNDS, image_provider=_camera)
    for f in _frames():
        scene.draw(f)
    cam, dens = scene.nodes.camera, scene.nodes.density
    assert cam is not None and cam.visible and dens.visible
    assert dens.position[2] > cam.position[2]  # drawn above the picture
    img = dens.image
    assert img.shape[2] == 4 and dens._format == "png"  # with an alpha channel, kept by PNG
    alpha = img[:, :, 3]
    assert alpha.max() < 255 and alpha.min() < alpha.max()  # translucent everywhere, denser = more opaque


def test_without_a_camera_picture_the_heat_map_stays_opaque(server) -> None:
    server.scene.reset()
    scene = ArenaScene(server, BOUNDS, image_provider=_camera)
    frames = _frames()
    scene.draw(frames[0])
    scene.set_layer("camera", False)
    scene.draw(frames[1])
    assert scene.nodes.density.image.shape[2] == 3
    scene.set_layer("camera", True)
    scene.draw(frames[2])
    assert scene.nodes.density.image.shape[2] == 4
    server.scene.reset()
    plain = ArenaScene(server, BOUNDS)  # simulation: no camera at all
    plain.draw(frames[0])
    assert plain.nodes.density.image.shape[2] == 3
