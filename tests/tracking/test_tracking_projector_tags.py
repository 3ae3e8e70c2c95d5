"""Robots' ArUco tags stay detectable under the projected image: the synthetic camera sees the console's density
heat map projected over the floor and the robots, and the tracker's detector finds the tags at least as often as
without the projection, less a small margin."""
from __future__ import annotations

import numpy as np

from swarmdeck.console.picture.heat import heatmap
from swarmdeck.core.bounds import DEFAULT_BOUNDS
from swarmdeck.coverage.density import GaussianMixture
from swarmdeck.tracking.detector import MarkerDetector
from swarmdeck.tracking.markers import DEFAULT_REFERENCES
from swarmdeck.tracking.projector import SyntheticProjector, warp_to_projector
from swarmdeck.tracking.synthetic import SyntheticCameraConfig, SyntheticRenderer, random_poses

N, SCENES = 30, 4
MARGIN = 0.03


def test_tag_detection_under_the_projected_density_matches_detection_without():
    r = SyntheticRenderer(SyntheticCameraConfig())
    det = MarkerDetector("DICT_4X4_50", DEFAULT_REFERENCES)
    proj = SyntheticProjector()
    density = GaussianMixture(0.05, np.array([[0.4, 0.2], [-0.8, -0.4]]), np.array([0.35, 0.3]), np.array([1.0, 0.8]))
    light = warp_to_projector(heatmap(density, DEFAULT_BOUNDS, 50.0), DEFAULT_BOUNDS, proj.homography(), proj.size)
    assert light.mean() > 60  # the projector really lights the arena
    found = {"without": 0, "with": 0}
    rng = np.random.default_rng(3)
    for _ in range(SCENES):
        poses = random_poses(N, rng, DEFAULT_BOUNDS)
        ids = np.arange(N)
        for key, projection in (("without", None), ("with", (light, proj.homography()))):
            frame = r.render(ids, poses, rng=np.random.default_rng(5), projection=projection)
            d = det.detect(frame.image[..., 1])
            found[key] += int(np.isin(ids, d.ids).sum())
    total = N * SCENES
    rate_without, rate_with = found["without"] / total, found["with"] / total
    assert rate_without >= 0.9
    assert rate_with >= rate_without - MARGIN, (rate_with, rate_without)
