"""The scene's filled Voronoi cells (layer "cells", off by default) are the picture's cells: one triangle fan per
cell, shaded by mass; a Frame without coverage removes them."""
from __future__ import annotations

import dataclasses

import numpy as np
import viser

from swarmdeck.console.picture import picture_of
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.console.web.scene import ArenaScene


def test_cells_are_drawn_from_the_picture_and_removed_without_coverage() -> None:
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    try:
        loop = ControlLoop(LoopConfig(seed=2, n_robots=7))
        frame = [loop.tick() for _ in range(3)][-1]
        pic = picture_of(frame)
        assert len(pic.cell_offsets) == frame.n + 1 and pic.cell_shades.shape == (frame.n, 3)
        heaviest = int(np.argmax(frame.coverage.masses))
        np.testing.assert_allclose(pic.cell_shades[heaviest], [60, 110, 220])  # the heaviest cell: full blue
        scene = ArenaScene(server)
        scene.draw(frame)
        assert scene.nodes.cells is None  # off by default
        scene.set_layer("cells", True)
        scene.draw(frame)
        assert scene.nodes.cells is not None
        scene.draw(dataclasses.replace(frame, tick=frame.tick + 1, coverage=None))
        assert scene.nodes.cells is None
    finally:
        server.stop()
