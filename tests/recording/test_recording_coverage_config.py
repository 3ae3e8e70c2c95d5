"""A recording draws the coverage cells the console showed, also under a non-default coverage config.

The real console loop runs coverage with a tuned :class:`~swarmdeck.coverage.CoverageConfig` (a finer
quadrature, wider pre-conditioning margins) and the real
recorder writes it; the reader's cells, edges, neighbours, centroids and masses equal the loop's bit
for bit. A frame without the config (every recording made before it was stored) reads with the
defaults, as before.
"""
from __future__ import annotations

import json

import jsonschema
import numpy as np
import pytest

from swarmdeck.console.recording.codec import decode_frame, encode_frame
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.recording.recorder import Recorder, RecorderConfig
from swarmdeck.console.recording.schemas import CHANNELS, TOPIC_FRAME
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.coverage import CoverageConfig, CoverageController
from swarmdeck.coverage.quadrature import QuadratureOptions

GEOMETRY = ("edges", "neighbours", "cell_vertices", "cell_offsets", "centroids", "masses")


class TunedCoverage:
    """The coverage behaviour with a configuration of its own (what ``ControlLoop.use_behaviour`` takes)."""

    name = "coverage"

    def __init__(self, config: CoverageConfig) -> None:
        self.config = config
        self._ctrl: CoverageController | None = None

    def __call__(self, tick):
        if self._ctrl is None:
            self._ctrl = CoverageController(self.config, tick.density)
        return self._ctrl(tick.points, tick.t)


def tuned_config(bounds) -> CoverageConfig:
    return CoverageConfig(bounds=bounds, wall_margin=0.009, min_separation=0.09,
                          quadrature=QuadratureOptions(resolution=0.4, min_level=1, max_level=6))


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """Frames of the console loop under the tuned config, and what the reader makes of their recording."""
    loop = ControlLoop(LoopConfig(n_robots=8, seed=4))
    try:
        loop.use_behaviour(TunedCoverage(tuned_config(loop.config.bounds)))
        frames = [loop.tick() for _ in range(12)]
    finally:
        loop.close()
    path = tmp_path_factory.mktemp("covcfg") / "tuned.mcap"
    with Recorder(path, config=RecorderConfig(foxglove=False)) as rec:
        for f in frames:
            rec.write_frame(f)
    with open_recording(path) as r:
        got = [f for _, f in r.frames()]
    assert all(f.coverage is not None and len(f.coverage.cell_offsets) == f.n + 1 for f in frames)
    return frames, got


def test_recorded_cells_are_the_cells_the_loop_drew(run):
    frames, got = run
    assert frames and len(got) == len(frames)
    for f, g in zip(frames, got):
        for name in GEOMETRY:
            assert np.array_equal(getattr(g.coverage, name), getattr(f.coverage, name)), name


def test_the_default_geometry_would_have_drawn_other_cells(run):
    """The check above has teeth: read without the stored config (an old file), the same frame
    derives the default geometry, which differs from what the loop drew."""
    frames, _ = run
    msg = json.loads(encode_frame(frames[-1]))
    assert msg["coverage"].get("config"), "the non-default coverage config is stored with the frame"
    del msg["coverage"]["config"]
    old = decode_frame(json.dumps(msg).encode())
    assert not all(np.array_equal(getattr(old.coverage, k), getattr(frames[-1].coverage, k)) for k in GEOMETRY)


def test_a_default_config_stores_nothing_extra():
    loop = ControlLoop(LoopConfig(n_robots=5, seed=2))
    try:
        frame = loop.tick()
    finally:
        loop.close()
    assert frame.coverage is not None
    assert "config" not in json.loads(encode_frame(frame))["coverage"]


def test_a_bad_stored_config_is_a_clear_error(run):
    frames, _ = run
    msg = json.loads(encode_frame(frames[-1]))
    msg["coverage"]["config"] = {"min_separation": -1.0}
    with pytest.raises(ValueError, match="coverage.config"):
        decode_frame(json.dumps(msg).encode())


def test_the_stored_config_is_in_the_frame_schema(run):
    """External readers (Foxglove, the mcap tools) see the stored config as a declared field."""
    frames, _ = run
    msg = json.loads(encode_frame(frames[-1]))
    jsonschema.validate(msg, CHANNELS[TOPIC_FRAME][1])
    assert set(msg["coverage"]["config"]) <= set(CHANNELS[TOPIC_FRAME][1]["properties"]["coverage"]["oneOf"][1]
                                                 ["properties"]["config"]["properties"])
