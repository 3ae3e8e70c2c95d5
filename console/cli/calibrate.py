"""``swarmdeck calibrate camera|arena`` — camera intrinsics and the arena's reference markers.

``calibrate camera``: intrinsics from ChArUco board images in a folder → calibration JSON
(``--write-board`` prints the board; ``--write-synthetic`` renders board views from the
synthetic camera to try it without hardware).

``calibrate arena``: detects the reference markers in one image (a file, or a frame from a
camera / video / folder / the synthetic camera), fits the floor homography from their surveyed
positions, reports the residuals and writes the tracker config (references, fallback homography,
camera position, calibration) that ``swarmdeck console --camera …`` loads. ``--measure IDS``
adds markers lying on the floor as further references at their measured positions.

``calibrate projector``: the projector shows an ArUco marker grid (``--write-pattern`` writes it), the camera
sees it, the camera's floor homography puts the markers on the floor, and the floor → projector homography is
fitted, its reprojection error reported in mm and saved (``projector.json`` next to the camera's config) for
``swarmdeck console --projector``. ``--camera synthetic`` runs the whole chain in simulation (a synthetic
projector lights the synthetic camera's floor).
"""
from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import cv2
import numpy as np

from swarmdeck.console.cli import UsageError

NAME = "calibrate"
HELP = "calibrate the overhead camera (ChArUco intrinsics), the arena (reference markers) or the projector"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """``camera`` and ``arena`` sub-subcommands."""
    sub = parser.add_subparsers(dest="what", metavar="camera|arena|projector", required=True)
    cam = sub.add_parser("camera", help="intrinsics from ChArUco board images in a folder")
    cam.add_argument("--images", type=Path, help="folder of board images (png/jpg/…)")
    cam.add_argument("--out", type=Path, default=Path("camera_calibration.json"), help="calibration JSON to write")
    cam.add_argument("--squares", default="7x5", help="board squares, COLSxROWS (default 7x5)")
    cam.add_argument("--square-length", type=float, default=0.04, help="square side in m (default 0.04)")
    cam.add_argument("--marker-length", type=float, default=0.03, help="marker side in m (default 0.03)")
    cam.add_argument("--dictionary", default="DICT_5X5_100", help="board dictionary: any OpenCV ArUco dictionary or AprilTag family, case-insensitive (default DICT_5X5_100)")
    cam.add_argument("--write-board", type=Path, metavar="PNG", help="write a printable board image and exit")
    cam.add_argument("--write-synthetic", type=Path, metavar="DIR",
                     help="render N synthetic board views (see --views) into DIR and exit")
    cam.add_argument("--views", type=int, default=15, help="number of synthetic views (default 15)")
    cam.add_argument("--seed", type=int, default=0, help="seed of the synthetic views")

    ar = sub.add_parser("arena", help="detect the reference markers and write the tracker config")
    src = ar.add_mutually_exclusive_group(required=True)
    src.add_argument("--image", type=Path, help="an image of the arena")
    src.add_argument("--camera", help="camera spec: webcam index, stream URL, video file, folder, or 'synthetic'")
    ar.add_argument("--calibration", type=Path, help="camera calibration JSON (from `calibrate camera`)")
    ar.add_argument("--config", type=Path, help="existing tracker config to start from (reference layout etc.)")
    ar.add_argument("--out", type=Path, default=Path("arena.json"), help="tracker config JSON to write")
    ar.add_argument("--tag-height", type=float, help="robot tag height above the floor, m")
    ar.add_argument("--measure", default="", help="comma-separated marker ids on the floor to add as references")
    ar.add_argument("--timeout", type=float, default=5.0, help="seconds to wait for a camera frame")

    pr = sub.add_parser("projector", help="fit the floor → projector homography from a projected marker grid",
                        description="Show the pattern on the projector (--write-pattern, then open it full screen "
                        "on the projector's display), then run this with the camera (or a photo) to fit the floor "
                        "→ projector homography; --camera synthetic does it all in simulation.")
    psrc = pr.add_mutually_exclusive_group()
    psrc.add_argument("--image", type=Path, help="a camera image of the projected pattern")
    psrc.add_argument("--camera", help="camera spec: webcam index, stream URL, video file, folder, or 'synthetic' "
                      "(a synthetic projector lights the synthetic camera's floor)")
    pr.add_argument("--config", type=Path, help="tracker config from `calibrate arena` (its homography and "
                    "calibration; without one the reference markers in the image give the floor homography)")
    pr.add_argument("--size", default=None, metavar="WxH",
                    help="the projector's resolution in px (default 1280x800; synthetic: the synthetic projector's)")
    pr.add_argument("--markers", default="8x5", metavar="COLSxROWS", help="pattern grid (default 8x5)")
    pr.add_argument("--out", type=Path, default=None,
                    help="projector calibration JSON to write (default projector.json next to --config, else here)")
    pr.add_argument("--write-pattern", type=Path, metavar="PNG", help="write the pattern image and exit")
    pr.add_argument("--timeout", type=float, default=5.0, help="seconds to wait for a camera frame")
    pr.add_argument("--synthetic-tilt", type=float, default=0.12, metavar="RAD",
                    help="synthetic projector's tilt from vertical (default 0.12 rad)")
    pr.add_argument("--synthetic-roll", type=float, default=0.0, metavar="RAD", help="synthetic projector's roll")
    pr.add_argument("--synthetic-light", type=float, default=0.7, metavar="K",
                    help="the projector's share of the light on the synthetic floor, 0–1 (default 0.7; "
                         "low = strong ambient light)")


def _squares(text: str) -> tuple[int, int]:
    try:
        a, b = (int(v) for v in text.lower().split("x"))
    except ValueError as exc:
        raise UsageError(f"--squares must look like 7x5, got {text!r}") from exc
    if a < 3 or b < 3:
        raise UsageError("--squares needs at least 3x3")
    return a, b


def _write_image(path: Path, image: np.ndarray, option: str) -> None:
    """cv2.imwrite, with its status checked (it returns False instead of raising)."""
    try:
        ok = cv2.imwrite(str(path), image)
    except cv2.error as exc:  # e.g. an unknown file extension
        raise UsageError(f"{option} {path}: cannot write the image ({exc.err})") from exc
    if not ok:
        raise UsageError(f"{option} {path}: cannot write the image (does the folder exist and is it writable?)")


def _camera(args: argparse.Namespace) -> int:
    from swarmdeck.tracking import CalibrationError, CharucoSpec, calibrate_charuco
    from swarmdeck.tracking.synthetic import SyntheticCameraConfig, charuco_views

    sx, sy = _squares(args.squares)
    try:
        spec = CharucoSpec(sx, sy, args.square_length, args.marker_length, args.dictionary)
        spec.board()
    except (CalibrationError, ValueError) as exc:
        raise UsageError(str(exc)) from exc
    if args.write_board:
        _write_image(args.write_board, spec.image(), "--write-board")
        print(f"wrote {args.write_board} ({sx}×{sy} squares of {args.square_length * 1000:g} mm; print at that size)")
        return 0
    if args.write_synthetic:
        if args.views < 1:
            raise UsageError(f"--views must be >= 1, got {args.views}")
        if args.seed < 0:
            raise UsageError(f"--seed must be a non-negative integer, got {args.seed}")
        try:
            args.write_synthetic.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise UsageError(f"--write-synthetic {args.write_synthetic}: cannot create the folder: "
                             f"{exc.strerror or exc}") from exc
        cam = SyntheticCameraConfig().camera()
        views = charuco_views(cam, spec, args.views, np.random.default_rng(args.seed))
        for k, img in enumerate(views):
            _write_image(args.write_synthetic / f"board_{k:03d}.png", img[..., ::-1], "--write-synthetic")
        print(f"wrote {len(views)} synthetic views to {args.write_synthetic} (true fx {cam.K[0, 0]:.1f} px, "
              f"dist {np.round(cam.dist, 4).tolist()})")
        return 0
    if args.images is None:
        raise UsageError("give --images DIR (or --write-board / --write-synthetic)")
    if not args.images.is_dir():
        raise UsageError(f"--images {args.images} is not a folder")
    from swarmdeck.tracking.imageread import IMAGE_SUFFIXES, ImageReadError, read_image
    files = sorted(p for p in args.images.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES)
    images = []
    for p in files:
        try:
            images.append(cv2.cvtColor(read_image(p), cv2.COLOR_RGB2GRAY))
        except ImageReadError as exc:
            print(f"skipping unreadable {p.name}: {exc}")
    try:
        cal = calibrate_charuco(images, spec)
    except CalibrationError as exc:
        raise UsageError(f"{exc} (in {len(images)} readable images in {args.images})") from exc
    try:
        cal.save(args.out)
    except CalibrationError as exc:
        raise UsageError(f"--out: {exc}") from exc
    K = cal.camera_matrix
    print(f"calibrated from {cal.n_images}/{len(images)} images: fx {K[0, 0]:.1f} fy {K[1, 1]:.1f} "
          f"cx {K[0, 2]:.1f} cy {K[1, 2]:.1f} px, dist {np.round(cal.dist_coeffs, 4).tolist()}, "
          f"reprojection RMS {cal.rms_px:.3f} px → {args.out}")
    return 0


def _grab(spec: str, timeout: float) -> np.ndarray:
    from swarmdeck.tracking import CameraError, open_source

    kw: dict = {}
    if spec == "synthetic":
        kw = {"get_poses": lambda t: np.zeros((0, 3))}
    try:
        source = open_source(spec, paced=False, **kw)
    except CameraError as exc:
        raise UsageError(str(exc)) from exc
    try:
        t_end = time.monotonic() + timeout
        while time.monotonic() < t_end:
            frame = source.read(time.monotonic())
            if frame is not None:
                return frame.image
            time.sleep(0.05)
        raise UsageError(f"no frame from camera {spec!r} within {timeout:g} s: {source.status}")
    finally:
        source.close()


def _arena(args: argparse.Namespace) -> int:
    from swarmdeck.tracking import CalibrationError, CameraCalibration, ConfigError, ReferenceMarker, TrackerConfig
    from swarmdeck.tracking.detector import MarkerDetector
    from swarmdeck.tracking.homography import apply_homography, camera_centre_from_homography, fit_floor_homography
    from swarmdeck.tracking.markers import poses_from_corners, reference_corners
    from swarmdeck.tracking.tracker import check_image

    try:
        cfg = TrackerConfig.load(args.config) if args.config else TrackerConfig()
        if args.calibration:
            cfg = cfg.with_(calibration=CameraCalibration.load(args.calibration))
        if args.tag_height is not None:
            cfg = cfg.with_(tag_height=args.tag_height)
    except (ConfigError, CalibrationError) as exc:
        raise UsageError(str(exc)) from exc
    try:
        measure = [int(v) for v in args.measure.split(",") if v.strip()]
    except ValueError as exc:
        raise UsageError(f"--measure must be comma-separated ids, got {args.measure!r}") from exc
    if not (math.isfinite(args.timeout) and args.timeout > 0):
        raise UsageError(f"--timeout must be a finite number of seconds > 0, got {args.timeout}")
    cal = cfg.calibration
    if args.image is not None:
        if not args.image.is_file():
            raise UsageError(f"no such image {args.image}")
        from swarmdeck.tracking.imageread import ImageReadError, read_image
        try:
            image = read_image(args.image)
        except ImageReadError as exc:
            raise UsageError(f"cannot read image {exc}") from None
    else:
        image = _grab(args.camera, args.timeout)
    err = check_image(image, None if cal is None else cal.image_size)
    if err:
        raise UsageError(err)
    det = MarkerDetector(cfg.dictionary, cfg.references, None if cal is None else cal.camera_matrix,
                         None if cal is None else cal.dist_coeffs, cfg.threshold_windows).detect(cv2.cvtColor(image, cv2.COLOR_RGB2GRAY))
    und = det.corners if cal is None else cal.undistort(det.corners)
    ref_ids, ref_c = reference_corners(cfg.references)
    uniq, counts = np.unique(det.ids, return_counts=True)
    dup = set(uniq[counts > 1].tolist())
    found = [k for k, i in enumerate(ref_ids) if i in det.ids and i not in dup]
    rows = [int(np.flatnonzero(det.ids == ref_ids[k])[0]) for k in found]
    missing = [int(ref_ids[k]) for k in range(len(ref_ids)) if k not in found]
    print(f"found {len(found)}/{len(ref_ids)} reference markers" + (f"; missing ids {missing}" if missing else "")
          + (f"; duplicate ids {sorted(dup)}" if dup else ""))
    fit = fit_floor_homography(und[rows], ref_c[found], (image.shape[1], image.shape[0]), cfg.min_references,
                               cfg.max_reference_rms_m, cfg.max_anisotropy)
    if not fit.ok:
        raise UsageError(f"cannot calibrate the arena: {fit.reason}")
    res = np.linalg.norm(apply_homography(fit.H, und[rows]) - ref_c[found], axis=-1).mean(axis=1)
    for k, r in zip(found, res):
        print(f"  reference {int(ref_ids[k])}: residual {r * 1000:.2f} mm")
    changes: dict = {"fallback_homography": tuple(tuple(float(v) for v in row) for row in fit.H)}
    if cal is not None:
        C = camera_centre_from_homography(fit.H, cal.camera_matrix)
        if C is not None:
            changes["camera_position"] = tuple(float(v) for v in C)
            print(f"camera at x {C[0]:.3f} y {C[1]:.3f} m, {C[2]:.3f} m above the reference plane")
    refs = list(cfg.references)
    for mid in measure:
        k = np.flatnonzero(det.ids == mid)
        if mid in ref_ids:
            raise UsageError(f"--measure {mid}: already a reference marker")
        if len(k) != 1:
            raise UsageError(f"--measure {mid}: marker {'not found' if len(k) == 0 else 'seen more than once'}")
        c = apply_homography(fit.H, und[k])
        pose = poses_from_corners(c)[0]
        size = float(np.mean(np.linalg.norm(c[0] - np.roll(c[0], 1, axis=0), axis=1)))
        refs.append(ReferenceMarker(mid, round(float(pose[0]), 4), round(float(pose[1]), 4), round(size, 4),
                                    round(float(pose[2]), 4)))
        print(f"  measured marker {mid}: x {pose[0]:.4f} y {pose[1]:.4f} m, side {size * 1000:.1f} mm, "
              f"heading {math.degrees(pose[2]):.1f}°")
    try:
        out = cfg.with_(references=tuple(refs), **changes)
    except ConfigError as exc:
        raise UsageError(str(exc)) from exc
    try:
        out.save(args.out)
    except ConfigError as exc:
        raise UsageError(f"--out: {exc}") from exc
    print(f"homography from {fit.n_references} references, {fit.rms_m * 1000:.2f} mm RMS → {args.out}")
    return 0


def _size(text: str, option: str) -> tuple[int, int]:
    """``WxH`` → (w, h) whole numbers > 0 (UsageError naming ``option``)."""
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise UsageError(f"{option} must look like {'8x5' if option == '--markers' else '1280x800'}, "
                         f"got {text!r}") from None
    if w < 1 or h < 1:
        raise UsageError(f"{option} must be positive, got {text!r}")
    return w, h


def _projector(args: argparse.Namespace) -> int:
    from swarmdeck.tracking import CalibrationError, ConfigError, TrackerConfig
    from swarmdeck.tracking.projector import (
        ProjectorCalibration,
        ProjectorCalibrationError,
        SyntheticProjector,
        find_pattern,
        fit_projector,
        marker_pattern,
    )

    try:
        cfg = TrackerConfig.load(args.config) if args.config else TrackerConfig()
    except (ConfigError, CalibrationError) as exc:
        raise UsageError(str(exc)) from exc
    synthetic = args.camera == "synthetic"
    truth = None
    if synthetic:
        if not (math.isfinite(args.synthetic_light) and 0.0 < args.synthetic_light <= 1.0):
            raise UsageError(f"--synthetic-light must be in (0, 1], got {args.synthetic_light}")
        for option, value in (("--synthetic-tilt", args.synthetic_tilt), ("--synthetic-roll", args.synthetic_roll)):
            if not (math.isfinite(value) and abs(value) < 1.2):
                raise UsageError(f"{option} must be an angle in (-1.2, 1.2) rad, got {value}")
        sp = SyntheticProjector(tilt=args.synthetic_tilt, roll=args.synthetic_roll)
        size = sp.size if args.size is None else _size(args.size, "--size")
        if size != sp.size:
            sp = SyntheticProjector(width=size[0], height=size[1], tilt=args.synthetic_tilt, roll=args.synthetic_roll)
        truth = sp.homography()
    else:
        size = _size(args.size or "1280x800", "--size")
    cols, rows = _size(args.markers, "--markers")
    if cols < 2 or rows < 2:
        raise UsageError(f"--markers needs at least 2x2 markers, got {args.markers!r}")
    try:
        pattern = marker_pattern(size, cols, rows)
    except ProjectorCalibrationError as exc:
        raise UsageError(str(exc)) from exc
    if args.write_pattern:
        _write_image(args.write_pattern, pattern.image, "--write-pattern")
        print(f"wrote {args.write_pattern} ({size[0]}×{size[1]} px, {cols}×{rows} {pattern.dictionary} markers): "
              "show it full screen on the projector, then run `swarmdeck calibrate projector --camera …`")
        return 0
    if not (math.isfinite(args.timeout) and args.timeout > 0):
        raise UsageError(f"--timeout must be a finite number of seconds > 0, got {args.timeout}")
    cal = cfg.calibration
    if synthetic:
        from swarmdeck.tracking import CameraCalibration
        from swarmdeck.tracking.synthetic import SyntheticCameraConfig, SyntheticRenderer

        renderer = SyntheticRenderer(SyntheticCameraConfig(bounds=cfg.bounds, projection_strength=args.synthetic_light))
        cal = cal or CameraCalibration.from_camera(renderer.camera)
        dark = renderer.render([], np.zeros((0, 3))).image          # the projector off: the references
        lit = renderer.render([], np.zeros((0, 3)), projection=(pattern.image, truth)).image
    elif args.image is not None:
        if not args.image.is_file():
            raise UsageError(f"no such image {args.image}")
        from swarmdeck.tracking.imageread import ImageReadError, read_image
        try:
            lit = read_image(args.image)
        except ImageReadError as exc:
            raise UsageError(f"cannot read image {exc}") from None
        dark = lit
    elif args.camera is not None:
        lit = dark = _grab(args.camera, args.timeout)
    else:
        raise UsageError("give --camera SPEC or --image PNG (or --write-pattern PNG)")
    floor_h = _floor_homography(cfg, cal, dark)
    gray = cv2.cvtColor(lit, cv2.COLOR_RGB2GRAY)
    seen = find_pattern(gray, pattern, floor_h, None if cal is None else cal.undistort)
    n_all = len(pattern.ids)
    print(f"found {len(seen.ids)}/{n_all} pattern markers")
    fit = fit_projector(seen.floor_corners, seen.pattern_corners, cfg.bounds, size)
    if not fit.ok or fit.H is None:
        why = ("; is the projector on and showing the pattern full screen, is the room dark enough?"
               if len(seen.ids) < n_all // 2 else "")
        raise UsageError(f"cannot calibrate the projector: {fit.reason}{why}")
    out = args.out or (args.config.parent / "projector.json" if args.config else Path("projector.json"))
    try:
        ProjectorCalibration(fit.H, size, cfg.bounds, fit.rms_mm, len(seen.ids)).save(out)
    except ProjectorCalibrationError as exc:
        raise UsageError(f"--out: {exc}") from exc
    print(f"projector homography from {len(seen.ids)} markers ({fit.n_inliers} corners), reprojection error "
          f"{fit.rms_mm:.2f} mm RMS on the floor → {out}")
    if truth is not None:
        from swarmdeck.tracking.projector import homography_error_mm

        print(f"synthetic projector: {homography_error_mm(fit.H, truth, cfg.bounds):.2f} mm max from the truth "
              "over the arena")
    return 0


def _floor_homography(cfg, cal, image: np.ndarray) -> np.ndarray:
    """The camera's floor homography (undistorted px → m): the tracker config's, else fitted from the reference
    markers in ``image`` (UsageError naming why not)."""
    if cfg.fallback_homography is not None:
        return np.asarray(cfg.fallback_homography, dtype=float)
    from swarmdeck.tracking.detector import MarkerDetector
    from swarmdeck.tracking.homography import fit_floor_homography
    from swarmdeck.tracking.markers import reference_corners

    det = MarkerDetector(cfg.dictionary, cfg.references, None if cal is None else cal.camera_matrix,
                         None if cal is None else cal.dist_coeffs, cfg.threshold_windows).detect(
                             cv2.cvtColor(image, cv2.COLOR_RGB2GRAY))
    und = det.corners if cal is None else cal.undistort(det.corners)
    ref_ids, ref_c = reference_corners(cfg.references)
    found = [k for k, i in enumerate(ref_ids) if int(np.sum(det.ids == i)) == 1]
    rows = [int(np.flatnonzero(det.ids == ref_ids[k])[0]) for k in found]
    fit = fit_floor_homography(und[rows], ref_c[found], (image.shape[1], image.shape[0]), cfg.min_references,
                               cfg.max_reference_rms_m, cfg.max_anisotropy)
    if not fit.ok or fit.H is None:
        raise UsageError(f"no floor homography for the camera: {fit.reason} (run `swarmdeck calibrate arena` and "
                         "pass its --config)")
    return np.asarray(fit.H, dtype=float)


def main(args: argparse.Namespace) -> int:
    """Run ``calibrate camera``, ``calibrate arena`` or ``calibrate projector``."""
    if args.what == "projector":
        return _projector(args)
    return _camera(args) if args.what == "camera" else _arena(args)
