"""`swarmdeck example coverage`: runs the law on the simulated arena and prints an H(t) summary."""
from __future__ import annotations

import cv2
import pytest

from swarmdeck.console.cli import main
from swarmdeck.coverage import letter_image


def test_moving_density_summary(capsys):
    assert main(["example", "coverage", "--robots", "6", "--duration", "3", "--seed", "1",
                 "--rows", "4"]) == 0
    out = capsys.readouterr().out
    assert "safety filter:" in out and "0 failures" in out
    assert "| t (s) | H / ∫φ | mean ‖p − c‖ (m) |" in out
    rows = [line for line in out.splitlines() if line.startswith("| ") and line[2].isdigit()]
    assert len(rows) == 4
    assert "| mean |" in out


def test_image_density_from_a_file(tmp_path, capsys):
    path = tmp_path / "r.png"
    cv2.imwrite(str(path), letter_image("R", 60, 96))
    assert main(["example", "coverage", "--robots", "4", "--duration", "1", "--seed", "2",
                 "--density", f"image:{path}", "--law", "lloyd"]) == 0
    assert "density image:" in capsys.readouterr().out


@pytest.mark.parametrize("argv, message", [
    (["--density", "image:/no/such/file.png"], "not found"),
    (["--density", "spiral"], "--density"),
    (["--law", "voronoi"], "unknown coverage law"),
    (["--law", "tvd-c"], "tvd-c"),
    (["--robots", "0"], "--robots"),
    (["--kappa", "-1"], "kappa"),
])
def test_bad_arguments_are_usage_errors(argv, message, capsys):
    assert main(["example", "coverage", "--duration", "1", *argv]) == 2
    assert message in capsys.readouterr().err
