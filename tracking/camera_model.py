"""Pinhole camera with lens distortion, looking at the arena (pure geometry).

World frame = arena frame (x right, y up, z up, metres). Camera frame = OpenCV's (x right,
y down, z forward). ``x_cam = R @ x_world + t``; pixels follow OpenCV's pixel-centre convention
(pixel (u, v) covers [u−½, u+½] × [v−½, v+½]) and its distortion model
``(k1, k2, p1, p2, k3)``.
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np


@dataclass(frozen=True, eq=False)
class PinholeCamera:
    """Intrinsics K (3, 3), distortion (5,), extrinsics R (3, 3), t (3,), image size (w, h) px."""

    K: np.ndarray
    dist: np.ndarray
    R: np.ndarray
    t: np.ndarray
    size: tuple[int, int]

    @property
    def centre(self) -> np.ndarray:
        """(3,) camera centre in the world frame, m."""
        return -self.R.T @ self.t

    def project(self, points: np.ndarray) -> np.ndarray:
        """World points (M, 3) → distorted pixels (M, 2)."""
        p = np.asarray(points, dtype=np.float64).reshape(-1, 1, 3)
        if p.shape[0] == 0:
            return np.zeros((0, 2))
        rvec, _ = cv2.Rodrigues(self.R)
        px, _ = cv2.projectPoints(p, rvec, self.t.astype(np.float64), self.K, self.dist)
        return px.reshape(-1, 2)

    def plane_homography(self, z: float) -> np.ndarray:
        """3×3 H mapping plane-z=``z`` coordinates (X, Y, 1) to normalised undistorted camera
        coordinates (x/z, y/z, 1): ``H = [r1 r2 r3·z + t]``."""
        return np.column_stack([self.R[:, 0], self.R[:, 1], self.R[:, 2] * z + self.t])

    def normalised_pixel_grid(self, step: int = 2) -> np.ndarray:
        """(h, w, 2) undistorted normalised coordinates of every pixel centre.

        The distortion model is inverted iteratively (to 1e-10) on a grid every ``step`` px and
        interpolated bicubically in between (the map is smooth; interpolation error < 1e-3 px
        for webcam-like distortion); ``step`` 1 inverts every pixel."""
        w, h = self.size
        if not np.any(self.dist):
            u, v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
            return np.stack([(u - self.K[0, 2]) / self.K[0, 0], (v - self.K[1, 2]) / self.K[1, 1]], axis=-1)
        cu = np.arange(-2 * step, w + 3 * step, step, dtype=np.float64)
        cv_ = np.arange(-2 * step, h + 3 * step, step, dtype=np.float64)
        u, v = np.meshgrid(cu, cv_)
        pts = np.stack([u, v], axis=-1).reshape(-1, 1, 2)
        crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 40, 1e-10)
        coarse = cv2.undistortPointsIter(pts, self.K, self.dist, None, None, crit).reshape(len(cv_), len(cu), 2)  # type: ignore[call-overload]  # cv2's stubs
        if step == 1:
            return coarse[2:2 + h, 2:2 + w].astype(np.float64)
        fu, fv = np.meshgrid((np.arange(w) + 2 * step) / step, (np.arange(h) + 2 * step) / step)
        # interpolate the offset from the undistorted-linear map (small values → float32 is exact enough)
        lin = np.stack([(u - self.K[0, 2]) / self.K[0, 0], (v - self.K[1, 2]) / self.K[1, 1]], axis=-1)
        delta = (coarse - lin).astype(np.float32)
        d = cv2.remap(delta, fu.astype(np.float32), fv.astype(np.float32), cv2.INTER_CUBIC,
                      borderMode=cv2.BORDER_REPLICATE)
        uu, vv = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
        base = np.stack([(uu - self.K[0, 2]) / self.K[0, 0], (vv - self.K[1, 2]) / self.K[1, 1]], axis=-1)
        return base + d


def look_at_rotation(centre: np.ndarray, target: np.ndarray, roll: float = 0.0) -> np.ndarray:
    """World→camera rotation R (3, 3) for a camera at ``centre`` looking at ``target`` with
    image up ≈ arena +y (then rolled by ``roll`` rad about the optical axis)."""
    z = np.asarray(target, float) - np.asarray(centre, float)
    z /= np.linalg.norm(z)
    x = np.cross(z, [0.0, 1.0, 0.0])
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    c, s = np.cos(roll), np.sin(roll)
    x, y = c * x + s * y, -s * x + c * y
    return np.stack([x, y, z])


def overhead_camera(
    size: tuple[int, int],
    height: float,
    tilt: float,
    tilt_azimuth: float,
    roll: float,
    look_at: tuple[float, float],
    view_bounds: tuple[float, float, float, float],
    dist: np.ndarray,
    focal_px: float | None = None,
    margin_px: float = 8.0,
) -> PinholeCamera:
    """A camera ``height`` m above the floor whose optical axis meets the floor at ``look_at``
    at ``tilt`` rad from vertical; the camera sits on the side opposite ``tilt_azimuth`` (so the
    far edge, in that direction, appears shorter: keystone). The focal length (px) is fitted so
    the floor rectangle ``view_bounds`` fills the image up to ``margin_px`` unless given."""
    w, h = size
    a = np.array([np.cos(tilt_azimuth), np.sin(tilt_azimuth)])
    target = np.array([look_at[0], look_at[1], 0.0])
    centre = np.array([*(np.array(look_at) - a * height * np.tan(tilt)), height])
    R = look_at_rotation(centre, target, roll)
    t = -R @ centre
    if focal_px is None:
        x0, x1, y0, y1 = view_bounds
        s = np.linspace(0.0, 1.0, 21)
        edge = np.concatenate([
            np.column_stack([x0 + (x1 - x0) * s, np.full_like(s, y0)]),
            np.column_stack([x0 + (x1 - x0) * s, np.full_like(s, y1)]),
            np.column_stack([np.full_like(s, x0), y0 + (y1 - y0) * s]),
            np.column_stack([np.full_like(s, x1), y0 + (y1 - y0) * s]),
        ])
        pc = np.column_stack([edge, np.zeros(len(edge))]) @ R.T + t
        n = pc[:, :2] / pc[:, 2:3]
        focal_px = float(min((w / 2 - margin_px) / np.abs(n[:, 0]).max(),
                             (h / 2 - margin_px) / np.abs(n[:, 1]).max()))
    K = np.array([[focal_px, 0.0, (w - 1) / 2], [0.0, focal_px, (h - 1) / 2], [0.0, 0.0, 1.0]])
    return PinholeCamera(K=K, dist=np.asarray(dist, float).reshape(-1), R=R, t=t, size=(w, h))
