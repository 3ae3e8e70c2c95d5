"""Tracking benchmark: detection + poses per frame on one core, accuracy, and latency.

Run: ``.venv/bin/python bench/bench_tracking.py`` (prints a markdown table).

Scenarios (issue 9 targets): 1280×720 with 20 robots (+4 references) ≤ 15 ms, 1920×1080 with
50 tags (46 robots + 4 references) ≤ 30 ms, ``cv2.setNumThreads(1)``. Time per frame is
``Tracker.update`` (grey conversion, detection, reference recovery, undistortion, homography,
parallax, poses) as process CPU time — on one thread that is the time on one core, and it is
robust to other processes sharing the machine; wall time is shown too. Baseline in the same
process: OpenCV's ``ArucoDetector`` with default parameters, detection only. Latency: a
``CameraPoseSource`` on the synthetic camera, from the end of rendering (capture) to poses.
"""
from __future__ import annotations

import argparse
import platform
import statistics
import time

import cv2
import harness  # first: pins BLAS/OpenMP to one thread, before numpy loads
import numpy as np

from swarmdeck.core.constants import CONTROL_PERIOD
from swarmdeck.tracking import (
    CameraCalibration,
    CameraFrame,
    CameraPoseSource,
    SyntheticCamera,
    SyntheticCameraConfig,
    SyntheticRenderer,
    Tracker,
    TrackerConfig,
    random_poses,
)

_cpu = harness.cpu_name


def scenario(width: int, height: int, n_robots: int, frames: int, rounds: int, seed: int) -> dict:
    r = SyntheticRenderer(SyntheticCameraConfig(width=width, height=height))
    rng = np.random.default_rng(seed)
    truths = [random_poses(n_robots, rng, min_distance=0.2) for _ in range(frames)]
    images = [r.render(np.arange(n_robots), t, rng=rng).image for t in truths]
    cfg = TrackerConfig(calibration=CameraCalibration.from_camera(r.camera))
    baseline = cv2.aruco.ArucoDetector(cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_50))
    grays = [cv2.cvtColor(im, cv2.COLOR_RGB2GRAY) for im in images]
    t_track, t_base, c_track = [], [], []
    errs, seen = [], 0
    for rd in range(rounds + 1):                  # round 0 warms up
        for k, im in enumerate(images):
            tracker = Tracker(cfg)
            c0 = time.process_time()
            t0 = time.perf_counter()
            tp = tracker.update(CameraFrame(im, float(k)))
            t1 = time.perf_counter()
            c1 = time.process_time()
            baseline.detectMarkers(grays[k])
            c2 = time.process_time()
            if rd > 0:
                t_track.append(t1 - t0)
                c_track.append(c1 - c0)
                t_base.append(c2 - c1)
            if rd == 1:
                rows = np.searchsorted(tp.ids, np.arange(n_robots))
                ok = (rows < len(tp.ids)) & (tp.ids[np.minimum(rows, len(tp.ids) - 1)] == np.arange(n_robots))
                ok &= tp.seen[np.minimum(rows, len(tp.ids) - 1)]
                seen += int(ok.sum())
                e = tp.poses[rows[ok]] - truths[k][ok]
                e[:, 2] = np.angle(np.exp(1j * e[:, 2]))
                errs.append(e)
    e = np.concatenate(errs)
    med, base = statistics.median(c_track), statistics.median(t_base)
    return {
        "name": f"{width}×{height}, {n_robots} robots + 4 refs",
        "median_ms": 1000 * med, "min_ms": 1000 * min(c_track), "wall_ms": 1000 * statistics.median(t_track),
        "base_ms": 1000 * base, "ratio": med / base,
        "detected": f"{seen}/{n_robots * frames}",
        "pos_mm": 1000 * float(np.sqrt(np.mean(np.sum(e[:, :2] ** 2, axis=1)))),
        "head_deg": float(np.degrees(np.sqrt(np.mean(e[:, 2] ** 2)))),
        "renderer": r,
    }


def latency(r: SyntheticRenderer, n_robots: int, ticks: int) -> dict:
    p = random_poses(n_robots, np.random.default_rng(7))
    cam = SyntheticCamera(lambda t: p, ids=range(n_robots), renderer=r)
    src = CameraPoseSource(cam, Tracker(TrackerConfig(calibration=CameraCalibration.from_camera(r.camera))))
    lat, render = [], []
    for k in range(ticks + 2):
        src.read(CONTROL_PERIOD * k)
        if k >= 2:
            lat.append(src.health()["latency_ms"])
    rng = np.random.default_rng(3)
    for _ in range(ticks):
        c0 = time.process_time()
        r.render(np.arange(n_robots), p, rng=rng)
        render.append(1000 * (time.process_time() - c0))
    return {"latency_ms": statistics.median(lat), "render_ms": statistics.median(render)}


def detection_ab(frames: int) -> list[str]:
    """Detections (of robots + references) and detection CPU time: REFERENCE.md §7 settings
    alone (OpenCV's other defaults) vs swarmdeck's (plus threshold windows and 8 px/cell)."""
    from swarmdeck.tracking.detector import detector_parameters

    d = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_4X4_50)
    ref7 = cv2.aruco.DetectorParameters()
    ref7.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
    ref7.relativeCornerRefinmentWinSize = 1.0
    dets = {"§7 only": cv2.aruco.ArucoDetector(d, ref7), "swarmdeck": cv2.aruco.ArucoDetector(d, detector_parameters())}
    cases = [("1280×720 default noise", SyntheticCameraConfig(), 20),
             ("1280×720 harsh (noise σ 6, blur σ 1.0, JPEG q70)",
              SyntheticCameraConfig(noise_sigma=6.0, blur_sigma=1.0, jpeg_quality=70), 20),
             ("1920×1080 default noise", SyntheticCameraConfig(width=1920, height=1080), 46)]
    lines = ["| frames | detected, §7 only | detected, swarmdeck | detection CPU ms median, §7 only | swarmdeck |",
             "| --- | --- | --- | --- | --- |"]
    for name, cfg, n in cases:
        r = SyntheticRenderer(cfg)
        rng = np.random.default_rng(5)
        grays = [cv2.cvtColor(r.render(np.arange(n), random_poses(n, rng), rng=rng).image, cv2.COLOR_RGB2GRAY)
                 for _ in range(frames)]
        found, cpu = {}, {}
        for key, det in dets.items():
            found[key], ts = 0, []
            for g in grays:
                c0 = time.process_time()
                _, ids, _ = det.detectMarkers(g)
                ts.append(time.process_time() - c0)
                found[key] += 0 if ids is None else len(ids)
            cpu[key] = 1000 * statistics.median(ts)
        total = (n + 4) * frames
        lines.append(f"| {name}, {frames} frames | {found['§7 only']}/{total} | {found['swarmdeck']}/{total} | "
                     f"{cpu['§7 only']:.1f} | {cpu['swarmdeck']:.1f} |")
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=5)
    ap.add_argument("--rounds", type=int, default=6)
    ap.add_argument("--ab-frames", type=int, default=25)
    args = ap.parse_args()
    cv2.setNumThreads(1)
    rows = [scenario(1280, 720, 20, args.frames, args.rounds, 1), scenario(1920, 1080, 46, args.frames, args.rounds, 2)]
    lat = [latency(rows[0]["renderer"], 20, 20), latency(rows[1]["renderer"], 46, 20)]
    print(f"cv2 {cv2.__version__}, cv2.setNumThreads(1), {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, "
          f"{_cpu()}, {platform.python_version()}\n")
    print("| scenario | tracker CPU ms median (min) | tracker wall ms median | baseline detectMarkers "
          "(OpenCV default params) CPU ms | ratio | detected | position RMS mm | heading RMS ° "
          "| capture→poses latency ms (wall) | synthetic render CPU ms |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for row, la in zip(rows, lat):
        print(f"| {row['name']} | {row['median_ms']:.1f} ({row['min_ms']:.1f}) | {row['wall_ms']:.1f} | "
              f"{row['base_ms']:.1f} | "
              f"{row['ratio']:.2f} | {row['detected']} | {row['pos_mm']:.2f} | {row['head_deg']:.2f} | "
              f"{la['latency_ms']:.1f} | {la['render_ms']:.1f} |")
    print()
    print("\n".join(detection_ab(args.ab_frames)))


if __name__ == "__main__":
    main()
