"""`swarmdeck calibrate`: unwritable outputs and bad board settings are one line and exit 2."""
import numpy as np
import pytest

from swarmdeck.console.cli import main
from swarmdeck.tracking import CalibrationError, CharucoSpec, ConfigError, TrackerConfig


@pytest.mark.parametrize("argv", [
    ["camera", "--write-board", "{tmp}/missing/board.png"],
    ["camera", "--write-board", "{tmp}/board.unknown-extension"],
    ["camera", "--write-synthetic", "{tmp}/views", "--views", "0"],
    ["camera", "--write-synthetic", "{tmp}/file.txt/views"],
    ["camera", "--images", "{tmp}", "--square-length", "nan"],
    ["camera", "--images", "{tmp}", "--square-length", "-1"],
    ["arena", "--camera", "synthetic", "--tag-height", "nan"],
    ["arena", "--camera", "synthetic", "--timeout", "-1"],
    ["arena", "--camera", "synthetic", "--out", "{tmp}/missing/arena.json"],
])
def test_mistakes_are_one_line_and_exit_2(argv, tmp_path, capsys):
    (tmp_path / "file.txt").write_text("x")
    assert main(["calibrate", *[a.format(tmp=tmp_path) for a in argv]]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "board.unknown-extension").exists()


def test_board_written_when_it_says_so(tmp_path, capsys):
    out = tmp_path / "board.png"
    assert main(["calibrate", "camera", "--write-board", str(out)]) == 0
    assert out.stat().st_size > 0 and "wrote" in capsys.readouterr().out


def test_calibration_out_unwritable(tmp_path, capsys):
    views = tmp_path / "views"
    assert main(["calibrate", "camera", "--write-synthetic", str(views), "--views", "6"]) == 0
    assert main(["calibrate", "camera", "--images", str(views), "--out", str(tmp_path)]) == 2  # a folder
    assert "cannot write calibration file" in capsys.readouterr().err


@pytest.mark.parametrize("kw", [{"square_length": float("nan")}, {"marker_length": 0.0}, {"squares_x": 2},
                                {"marker_length": 0.05}])
def test_board_spec_checked(kw):
    with pytest.raises(CalibrationError):
        CharucoSpec(**kw)


@pytest.mark.parametrize("kw", [{"tag_height": np.nan}, {"reference_height": -0.1}, {"max_reference_rms_m": np.inf},
                                {"camera_position": (0.0, np.nan, 2.5)}, {"stale_after_s": np.inf}])
def test_tracker_config_rejects_non_finite(kw):
    with pytest.raises(ConfigError):
        TrackerConfig(**kw)


@pytest.mark.parametrize("content", [b"\x89PNG\r\n\x1a\n\x00\x00binary", b"[1, 2]", b"{not json"])
@pytest.mark.parametrize("option", ["--calibration", "--config"])
def test_unusable_input_files_are_one_line(option, content, tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_bytes(content)
    assert main(["calibrate", "arena", "--camera", "synthetic", option, str(bad)]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1 and "bad.json" in err


def test_repeated_views_do_not_count(tmp_path):
    import cv2

    from swarmdeck.tracking import calibrate_charuco

    views = tmp_path / "views"
    assert main(["calibrate", "camera", "--write-synthetic", str(views), "--views", "6"]) == 0
    images = [cv2.imread(str(p), cv2.IMREAD_GRAYSCALE) for p in sorted(views.iterdir())]
    with pytest.raises(CalibrationError, match="1 distinct view"):
        calibrate_charuco([images[0]] * 6, CharucoSpec())
    assert calibrate_charuco(images, CharucoSpec()).n_images == 6
