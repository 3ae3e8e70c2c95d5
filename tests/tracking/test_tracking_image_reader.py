"""One image reader for the image-folder camera and `swarmdeck calibrate`: 16-bit PNGs
and float TIFFs are read (the folder source called them "cannot read"), and EXIF
orientation is applied by both (the folder source ignored it, `calibrate arena` did not)."""
from __future__ import annotations

import json
import struct

import cv2
import numpy as np
import pytest

from swarmdeck.console.cli import main
from swarmdeck.tracking import ImageFolderSource, open_source
from swarmdeck.tracking.imageread import ImageReadError, read_image


def exif_jpeg(rgb: np.ndarray, orientation: int) -> bytes:
    """A JPEG of ``rgb`` whose EXIF says ``orientation`` (an APP1 segment right after SOI)."""
    ok, buf = cv2.imencode(".jpg", cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR), [cv2.IMWRITE_JPEG_QUALITY, 98])
    assert ok
    tiff = b"MM\x00\x2a" + struct.pack(">I", 8) + struct.pack(">H", 1) \
        + struct.pack(">HHIHH", 0x0112, 3, 1, orientation, 0) + struct.pack(">I", 0)
    app1 = b"Exif\x00\x00" + tiff
    data = buf.tobytes()
    return data[:2] + b"\xff\xe1" + struct.pack(">H", len(app1) + 2) + app1 + data[2:]


@pytest.fixture(scope="module")
def arena_rgb() -> np.ndarray:
    cam = open_source("synthetic", get_poses=lambda t: np.zeros((0, 3)), paced=False)
    try:
        return cam.read(0.0).image
    finally:
        cam.close()


def test_16_bit_and_float_images_read_as_8_bit_rgb(tmp_path):
    rng = np.random.default_rng(3)
    rgb16 = rng.integers(0, 65536, (24, 32, 3), dtype=np.uint16)
    cv2.imwrite(str(tmp_path / "a16.png"), rgb16[..., ::-1])
    grey16 = rng.integers(0, 65536, (24, 32), dtype=np.uint16)
    cv2.imwrite(str(tmp_path / "b16grey.png"), grey16)
    f32 = rng.uniform(-0.2, 1.2, (24, 32, 3)).astype(np.float32)
    cv2.imwrite(str(tmp_path / "c32.tiff"), f32[..., ::-1])
    want = {
        "a16.png": np.round(rgb16 / 257.0).astype(np.uint8),
        "b16grey.png": np.repeat(np.round(grey16 / 257.0).astype(np.uint8)[..., None], 3, axis=2),
        "c32.tiff": np.round(np.clip(f32, 0, 1) * 255.0).astype(np.uint8),
    }
    src = ImageFolderSource(tmp_path)
    for k, name in enumerate(sorted(want)):
        img = read_image(tmp_path / name)
        assert img.dtype == np.uint8 and img.shape == (24, 32, 3)
        np.testing.assert_array_equal(img, want[name])
        frame = src.read(float(k))
        assert frame is not None, src.status
        np.testing.assert_array_equal(frame.image, img)
    assert src.unreadable == 0


def test_exif_orientation_is_applied(tmp_path):
    upright = np.zeros((40, 64, 3), np.uint8)
    upright[:10, :16] = (255, 0, 0)  # a red block top-left
    stored = np.ascontiguousarray(np.rot90(upright, 1))  # the camera stored it turned 90° left
    (tmp_path / "photo.jpg").write_bytes(exif_jpeg(stored, 6))  # 6: turn 90° right to display
    img = read_image(tmp_path / "photo.jpg")
    assert img.shape == upright.shape
    assert img[:10, :16, 0].mean() > 200 and img[:10, :16, 1:].mean() < 40
    frame = ImageFolderSource(tmp_path).read(0.0)
    np.testing.assert_array_equal(frame.image, img)


def test_unreadable_files_name_the_problem(tmp_path):
    (tmp_path / "junk.png").write_bytes(b"\x89PNG\r\n\x1a\nnot really")
    with pytest.raises(ImageReadError, match="junk.png"):
        read_image(tmp_path / "junk.png")
    with pytest.raises(ImageReadError, match="no such file"):
        read_image(tmp_path / "missing.png")
    src = ImageFolderSource(tmp_path)
    assert src.read(0.0) is None and src.unreadable == 1 and "junk.png" in src.status


def _homography(out) -> np.ndarray:
    return np.array(json.loads(out.read_text())["fallback_homography"])


@pytest.mark.parametrize("kind", ["png16", "exif-jpeg"])
def test_calibrate_arena_and_the_folder_camera_see_the_same_picture(kind, arena_rgb, tmp_path, capsys):
    folder = tmp_path / "frames"
    folder.mkdir()
    if kind == "png16":
        path = folder / "arena.png"
        cv2.imwrite(str(path), arena_rgb[..., ::-1].astype(np.uint16) * 257)
    else:
        path = folder / "arena.jpg"
        path.write_bytes(exif_jpeg(np.ascontiguousarray(np.rot90(arena_rgb, 1)), 6))
    a, b = tmp_path / "from_image.json", tmp_path / "from_folder.json"
    assert main(["calibrate", "arena", "--image", str(path), "--out", str(a)]) == 0, capsys.readouterr().err
    assert main(["calibrate", "arena", "--camera", str(folder), "--timeout", "2", "--out", str(b)]) == 0, \
        capsys.readouterr().err
    np.testing.assert_allclose(_homography(a), _homography(b), rtol=0, atol=1e-12)
    ref = tmp_path / "ref.json"
    cv2.imwrite(str(tmp_path / "ref.png"), arena_rgb[..., ::-1])
    assert main(["calibrate", "arena", "--image", str(tmp_path / "ref.png"), "--out", str(ref)]) == 0
    np.testing.assert_allclose(_homography(b), _homography(ref), rtol=2e-3, atol=2e-3)  # jpeg: ≈ the same
