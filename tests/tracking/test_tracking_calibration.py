"""Calibration round trip on synthetic ChArUco views, the calibration and config files, and the
``swarmdeck calibrate camera|arena`` commands end to end."""
from __future__ import annotations

import json

import numpy as np
import pytest

from swarmdeck.console.cli import main as cli
from swarmdeck.tracking import (
    CalibrationError,
    CameraCalibration,
    CameraFrame,
    CharucoSpec,
    ConfigError,
    SyntheticCameraConfig,
    SyntheticRenderer,
    Tracker,
    TrackerConfig,
    calibrate_charuco,
    random_poses,
)
from swarmdeck.tracking.synthetic import charuco_views


@pytest.fixture(scope="module")
def renderer() -> SyntheticRenderer:
    return SyntheticRenderer(SyntheticCameraConfig())


@pytest.fixture(scope="module")
def estimated(renderer) -> CameraCalibration:
    views = charuco_views(renderer.camera, CharucoSpec(), 12, np.random.default_rng(0))
    return calibrate_charuco(views, CharucoSpec())


def test_charuco_round_trip_recovers_the_lens(renderer, estimated) -> None:
    K = renderer.camera.K
    assert estimated.n_images == 12 and estimated.rms_px < 0.5
    assert abs(estimated.camera_matrix[0, 0] / K[0, 0] - 1) < 0.01
    assert np.allclose(estimated.camera_matrix[:2, 2], K[:2, 2], atol=5.0)
    assert abs(estimated.dist_coeffs[0] - renderer.camera.dist[0]) < 0.01


def test_tracking_with_the_estimated_calibration_meets_the_target(renderer, estimated) -> None:
    rng = np.random.default_rng(31)
    truth = random_poses(20, rng)
    tp = Tracker(TrackerConfig(calibration=estimated)).update(
        CameraFrame(renderer.render(np.arange(20), truth, rng=rng).image, 0.0))
    assert tp.seen.all() and len(tp.ids) == 20
    assert np.sqrt(np.mean(np.sum((tp.poses[:, :2] - truth[:, :2]) ** 2, axis=1))) <= 0.002


def test_calibration_and_config_files_round_trip(tmp_path, estimated) -> None:
    estimated.save(tmp_path / "cal.json")
    back = CameraCalibration.load(tmp_path / "cal.json")
    assert np.array_equal(back.camera_matrix, estimated.camera_matrix) and back.image_size == estimated.image_size
    cfg = TrackerConfig(calibration=back, expected_ids=(1, 2), camera_position=(0.0, -0.2, 2.6))
    cfg.save(tmp_path / "arena.json")
    again = TrackerConfig.load(tmp_path / "arena.json")
    assert again.to_dict() == cfg.to_dict()


@pytest.mark.parametrize("content, message", [
    ("{", "is not JSON"),
    ('{"camera_matrix": [[1, 0], [0, 1]], "dist_coeffs": [0, 0, 0, 0, 0], "image_size": [10, 10]}', "3×3"),
    ('{"camera_matrix": [[500, 0, 1], [0, 500, 1], [0, 0, 1]], "dist_coeffs": [0, 0], "image_size": [9, 9]}',
     "dist_coeffs must have"),
])
def test_bad_calibration_files_name_the_problem(tmp_path, content, message) -> None:
    p = tmp_path / "cal.json"
    p.write_text(content)
    with pytest.raises(CalibrationError, match=message):
        CameraCalibration.load(p)


def test_bad_tracker_config_names_the_field(tmp_path) -> None:
    p = tmp_path / "arena.json"
    p.write_text(json.dumps({"tag_size": 3.0}))
    with pytest.raises(ConfigError, match="tag_size"):
        TrackerConfig.load(p)
    p.write_text(json.dumps({"colour": "red"}))
    with pytest.raises(ConfigError, match="unknown tracker config key"):
        TrackerConfig.load(p)


def test_cli_calibrate_camera_then_arena(tmp_path, capsys) -> None:
    views = tmp_path / "views"
    assert cli(["calibrate", "camera", "--write-synthetic", str(views), "--views", "8", "--seed", "3"]) == 0
    cal = tmp_path / "cal.json"
    assert cli(["calibrate", "camera", "--images", str(views), "--out", str(cal)]) == 0
    assert "calibrated from 8/8 images" in capsys.readouterr().out
    arena = tmp_path / "arena.json"
    assert cli(["calibrate", "arena", "--camera", "synthetic", "--calibration", str(cal), "--out", str(arena)]) == 0
    out = capsys.readouterr().out
    assert "found 4/4 reference markers" in out and "camera at" in out
    cfg = TrackerConfig.load(arena)
    assert cfg.fallback_homography is not None and cfg.calibration is not None
    assert abs(cfg.camera_position[2] - SyntheticCameraConfig().camera_height) < 0.05
    assert cli(["calibrate", "arena", "--image", str(tmp_path / "none.png")]) == 2
    assert "no such image" in capsys.readouterr().err
    assert cli(["calibrate", "camera", "--images", str(tmp_path)]) == 2
    assert "found the ChArUco board in 0 distinct view(s)" in capsys.readouterr().err
