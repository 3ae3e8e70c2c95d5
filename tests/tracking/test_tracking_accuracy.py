"""Accuracy on synthetic 1280×720 frames with exact truth (issue 9 targets): 8 cm tags, default
noise (blur, noise, JPEG, vignetting), lens distortion corrected by the calibration, parallax of
6 cm tags corrected; all 20 robots detected."""
from __future__ import annotations

import numpy as np
import pytest

from swarmdeck.tracking import (
    CameraCalibration,
    CameraFrame,
    SyntheticCameraConfig,
    SyntheticRenderer,
    Tracker,
    TrackerConfig,
    random_poses,
)


@pytest.fixture(scope="module")
def renderer() -> SyntheticRenderer:
    return SyntheticRenderer(SyntheticCameraConfig())


def _errors(renderer: SyntheticRenderer, config: TrackerConfig, n: int, frames: int, seed: int):
    rng = np.random.default_rng(seed)
    tracker = Tracker(config)
    errs, seen = [], []
    for k in range(frames):
        truth = random_poses(n, rng)
        f = renderer.render(np.arange(n), truth, rng=rng)
        tp = tracker.update(CameraFrame(f.image, 0.1 * k))
        assert tp.homography == "ok", tp.status
        k_rows = np.searchsorted(tp.ids, np.arange(n))
        seen.append(tp.seen[k_rows] & (tp.ids[k_rows] == np.arange(n)))
        e = tp.poses[k_rows] - truth
        e[:, 2] = np.angle(np.exp(1j * e[:, 2]))
        errs.append(e[seen[-1]])
    return np.concatenate(errs), np.concatenate(seen)


def test_position_and_heading_rms_with_calibration_and_parallax(renderer: SyntheticRenderer) -> None:
    cfg = renderer.config
    assert cfg.width == 1280 and cfg.height == 720 and cfg.tag_size == 0.08 and cfg.tag_height > 0
    assert np.any(np.asarray(cfg.distortion) != 0) and cfg.noise_sigma > 0 and cfg.jpeg_quality is not None
    tc = TrackerConfig(calibration=CameraCalibration.from_camera(renderer.camera), tag_height=cfg.tag_height)
    e, seen = _errors(renderer, tc, n=20, frames=3, seed=11)
    assert seen.all(), "every one of the 20 robots must be detected in every frame"
    pos_rms = np.sqrt(np.mean(np.sum(e[:, :2] ** 2, axis=1)))
    head_rms = np.degrees(np.sqrt(np.mean(e[:, 2] ** 2)))
    assert pos_rms <= 0.002, f"position RMS {pos_rms * 1000:.2f} mm"
    assert head_rms <= 1.0, f"heading RMS {head_rms:.2f}°"


def test_uncorrected_distortion_and_parallax_are_centimetres(renderer: SyntheticRenderer) -> None:
    """The corrections matter: without calibration and parallax correction errors are far above
    the 2 mm target (so the test above cannot pass by accident)."""
    tc = TrackerConfig(tag_height=0.0)
    e, seen = _errors(renderer, tc, n=20, frames=1, seed=12)
    assert seen.all()
    assert np.sqrt(np.mean(np.sum(e[:, :2] ** 2, axis=1))) > 0.01
    # parallax alone: calibrated, but the tag height ignored
    tc = TrackerConfig(calibration=CameraCalibration.from_camera(renderer.camera), tag_height=0.0)
    e, _ = _errors(renderer, tc, n=20, frames=1, seed=12)
    assert np.sqrt(np.mean(np.sum(e[:, :2] ** 2, axis=1))) > 0.01


def test_parallax_from_configured_camera_position_without_calibration() -> None:
    """No lens distortion and no calibration: the configured camera position corrects parallax."""
    r = SyntheticRenderer(SyntheticCameraConfig(distortion=(0.0, 0.0, 0.0, 0.0, 0.0)))
    tc = TrackerConfig(camera_position=tuple(r.camera.centre), tag_height=r.config.tag_height)
    e, seen = _errors(r, tc, n=20, frames=1, seed=13)
    assert seen.all()
    assert np.sqrt(np.mean(np.sum(e[:, :2] ** 2, axis=1))) <= 0.002
