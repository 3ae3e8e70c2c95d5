"""Projector calibration in simulation: a synthetic projector lights the synthetic camera's floor with the marker
grid, the camera finds it, the floor → projector homography is fitted — within 5 mm of the truth across several
projector poses; with markers occluded it fits from what it sees, under strong ambient light it says how many
markers it found; bad homographies are refused with the reason."""
from __future__ import annotations

import json

import numpy as np
import pytest

from swarmdeck.console.cli import main as cli_main
from swarmdeck.core.bounds import DEFAULT_BOUNDS
from swarmdeck.tracking.calibration import CameraCalibration
from swarmdeck.tracking.projector import (
    ProjectorCalibration,
    ProjectorCalibrationError,
    SyntheticProjector,
    check_projector_homography,
    find_pattern,
    fit_projector,
    homography_error_mm,
    marker_pattern,
)
from swarmdeck.tracking.synthetic import SyntheticCameraConfig, SyntheticRenderer


@pytest.fixture(scope="module")
def renderer() -> SyntheticRenderer:
    return SyntheticRenderer(SyntheticCameraConfig())


def _camera_floor_h(r: SyntheticRenderer) -> np.ndarray:
    """The synthetic camera's exact floor homography (undistorted px → m)."""
    cal = CameraCalibration.from_camera(r.camera)
    H = np.linalg.inv(cal.camera_matrix @ r.camera.plane_homography(0.0))
    return H / H[2, 2]


def _calibrate(r: SyntheticRenderer, proj: SyntheticProjector, occlude: float = 0.0):
    pattern = marker_pattern(proj.size)
    image = pattern.image.copy()
    if occlude:  # something covers the left part of the projector's image
        image[:, : int(occlude * proj.width)] = 0
    frame = r.render([], np.zeros((0, 3)), projection=(image, proj.homography()))
    gray = frame.image[..., 1]
    seen = find_pattern(gray, pattern, _camera_floor_h(r), CameraCalibration.from_camera(r.camera).undistort)
    return seen, fit_projector(seen.floor_corners, seen.pattern_corners, DEFAULT_BOUNDS, proj.size)


POSES = [SyntheticProjector(),
         SyntheticProjector(tilt=0.25, roll=0.04, height_m=2.3),
         SyntheticProjector(tilt=0.18, tilt_azimuth=0.3, roll=-0.05, look_at=(0.1, -0.05), width=1024, height=768),
         SyntheticProjector(tilt=0.05, roll=0.02, width=1920, height=1080, view_bounds=(-1.9, 1.9, -1.2, 1.2))]


@pytest.mark.parametrize("proj", POSES, ids=["straight", "tilted", "keystone-1024", "1080p"])
def test_calibration_within_5_mm_across_projector_poses(renderer, proj):
    seen, fit = _calibrate(renderer, proj)
    assert fit.ok, fit.reason
    assert fit.H is not None
    assert fit.rms_mm <= 5.0
    assert homography_error_mm(fit.H, proj.homography(), DEFAULT_BOUNDS) <= 5.0
    assert len(seen.ids) >= 12


def test_partly_occluded_pattern_fits_from_what_it_sees(renderer):
    proj = SyntheticProjector()
    seen, fit = _calibrate(renderer, proj, occlude=0.4)
    assert fit.ok, fit.reason
    assert fit.H is not None
    assert 4 <= len(seen.ids) < 40 and int(seen.pattern_corners[:, :, 0].min()) > 0.4 * proj.width
    assert homography_error_mm(fit.H, proj.homography(), (-0.6, 1.6, -1.0, 1.0)) <= 5.0  # where it saw markers


def test_strong_ambient_light_says_how_many_markers_and_why_not_enough():
    r = SyntheticRenderer(SyntheticCameraConfig(projection_strength=0.04))
    seen, fit = _calibrate(r, SyntheticProjector())
    assert not fit.ok
    assert f"found {len(seen.ids)} pattern marker(s), need 4" in fit.reason


def test_cli_calibrates_the_synthetic_projector_and_saves_it(tmp_path, capsys):
    out = tmp_path / "projector.json"
    assert cli_main(["calibrate", "projector", "--camera", "synthetic", "--synthetic-tilt", "0.2",
                     "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "reprojection error" in text and "mm RMS" in text
    cal = ProjectorCalibration.load(out)
    assert cal.size == (1280, 800) and cal.rms_mm <= 5.0
    truth = SyntheticProjector(tilt=0.2).homography()
    assert homography_error_mm(cal.homography, truth, DEFAULT_BOUNDS) <= 5.0
    assert json.loads(out.read_text())["n_markers"] >= 20


def test_cli_under_strong_ambient_light_names_the_markers_found(tmp_path, capsys):
    assert cli_main(["calibrate", "projector", "--camera", "synthetic", "--synthetic-light", "0.04",
                     "--out", str(tmp_path / "p.json")]) != 0
    err = capsys.readouterr().err
    assert "pattern marker(s), need 4" in err and "dark enough" in err
    assert not (tmp_path / "p.json").exists()


def test_bad_homographies_are_refused_with_the_reason():
    size = (1280, 800)
    good = SyntheticProjector().homography()
    assert check_projector_homography(good, DEFAULT_BOUNDS, size) is None
    assert "singular" in check_projector_homography(np.diag([1.0, 1.0, 0.0]) @ good * 0 + np.outer([1, 2, 0], [1, 1, 1]),
                                                    DEFAULT_BOUNDS, size)
    assert "non-finite" in check_projector_homography(np.full((3, 3), np.nan), DEFAULT_BOUNDS, size)
    assert "3×3" in check_projector_homography(np.eye(2), DEFAULT_BOUNDS, size)
    off = np.array([[1.0, 0, 5000.0], [0, 1.0, 0], [0, 0, 1]]) @ good  # the arena lands 5000 px to the right
    assert "off the projector image" in check_projector_homography(off, DEFAULT_BOUNDS, size)
    horizon = good.copy()
    horizon[2] = [0.0, 1.0, 0.0]  # w = y: changes sign inside the arena
    assert "horizon" in check_projector_homography(horizon, DEFAULT_BOUNDS, size)
    with pytest.raises(ProjectorCalibrationError, match="off the projector image"):
        ProjectorCalibration(off, size, DEFAULT_BOUNDS)


def test_calibration_file_round_trips_and_bad_files_name_the_problem(tmp_path):
    cal = ProjectorCalibration(SyntheticProjector().homography(), (1280, 800), DEFAULT_BOUNDS, 1.2, 30)
    path = tmp_path / "projector.json"
    cal.save(path)
    back = ProjectorCalibration.load(path)
    assert np.allclose(back.homography, cal.homography) and back.size == cal.size and back.n_markers == 30
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"homography": [[1, 0], [0, 1]], "size": [1280, 800], "bounds": list(DEFAULT_BOUNDS)}))
    with pytest.raises(ProjectorCalibrationError, match="bad.json.*3×3"):
        ProjectorCalibration.load(bad)
    bad.write_text("{not json")
    with pytest.raises(ProjectorCalibrationError, match="not JSON"):
        ProjectorCalibration.load(bad)


@pytest.mark.parametrize("argv,words", [
    (["--markers", "3"], "--markers must look like 8x5"),
    (["--markers", "1x5"], "--markers needs at least 2x2"),
    (["--size", "100x50"], "6 px markers"),
    (["--synthetic-tilt", "nan"], "--synthetic-tilt must be an angle"),
    (["--synthetic-light", "0"], "--synthetic-light must be in (0, 1]"),
])
def test_cli_bad_options_name_the_option(tmp_path, capsys, argv, words):
    assert cli_main(["calibrate", "projector", "--camera", "synthetic", "--out", str(tmp_path / "p.json"), *argv]) != 0
    assert words in capsys.readouterr().err
    assert not (tmp_path / "p.json").exists()
