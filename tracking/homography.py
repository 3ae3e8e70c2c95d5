"""Floor homography from reference markers, its sanity checks, and parallax correction.

``H`` maps undistorted image pixels (u, v, 1) to arena metres (x, y, 1) on the plane of the
reference markers (REFERENCE.md §7: ``cv2.findHomography`` on the 16 reference corners; reject
with < 3 references or bad conditioning and keep the last good one).
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np


@dataclass(frozen=True, eq=False)
class HomographyFit:
    """Result of a fit: H (3, 3) or None, ok, reason (why rejected, "" if ok), n_references,
    rms_m (reference-corner residual in metres), anisotropy (singular-value ratio of the
    local pixel→metre Jacobian at the image centre)."""

    H: np.ndarray | None
    ok: bool
    reason: str
    n_references: int
    rms_m: float = float("nan")
    anisotropy: float = float("nan")


def apply_homography(H: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Map points (..., 2) through H (3, 3)."""
    p = np.asarray(pts, dtype=np.float64)
    if p.size == 0:
        return p.copy()
    return cv2.perspectiveTransform(p.reshape(-1, 1, 2), H).reshape(p.shape)


def fit_floor_homography(img_corners: np.ndarray, arena_corners: np.ndarray, image_size: tuple[int, int],
                         min_references: int = 3, max_rms_m: float = 0.01,
                         max_anisotropy: float = 10.0) -> HomographyFit:
    """Fit H from reference corners: image (R, 4, 2) undistorted px → arena (R, 4, 2) m.

    Rejected (ok False, reason set) when fewer than ``min_references`` markers, the fit fails,
    H is not finite or singular, the Jacobian at the image centre is degenerate or more
    anisotropic than ``max_anisotropy``, mirrors the wrong way (image y down must become arena
    y up), or the reference corners miss their surveyed positions by more than ``max_rms_m``
    RMS (a misdetected corner, a bent marker; a moved marker shows only with more than four
    references, since a homography fits any four centres).
    """
    img = np.asarray(img_corners, dtype=np.float64).reshape(-1, 4, 2)
    arena = np.asarray(arena_corners, dtype=np.float64).reshape(-1, 4, 2)
    n = len(img)
    if n < min_references:
        return HomographyFit(None, False, f"{n} reference marker(s) visible, need {min_references}", n)
    H, _ = cv2.findHomography(img.reshape(-1, 2), arena.reshape(-1, 2), 0)
    if H is None or not np.all(np.isfinite(H)) or abs(H[2, 2]) < 1e-12:
        return HomographyFit(None, False, "homography fit failed", n)
    H = H / H[2, 2]
    w, h = image_size
    c = np.array([(w - 1) / 2, (h - 1) / 2])
    eps = 1.0
    pts = apply_homography(H, np.array([c, c + [eps, 0], c + [0, eps]]))
    J = np.column_stack([pts[1] - pts[0], pts[2] - pts[0]]) / eps
    sv = np.linalg.svd(J, compute_uv=False)
    if not np.all(np.isfinite(sv)) or sv[1] <= 1e-12:
        return HomographyFit(None, False, "homography is singular at the image centre", n)
    aniso = float(sv[0] / sv[1])
    if np.linalg.det(J) >= 0:
        return HomographyFit(None, False, "homography has the wrong handedness (mirrored image?)", n,
                             anisotropy=aniso)
    rms = float(np.sqrt(np.mean(np.sum((apply_homography(H, img) - arena) ** 2, axis=-1))))
    if aniso > max_anisotropy:
        return HomographyFit(None, False, f"ill-conditioned homography (anisotropy {aniso:.1f} > {max_anisotropy})",
                             n, rms, aniso)
    if not rms <= max_rms_m:
        return HomographyFit(None, False, f"reference corners off by {rms * 1000:.1f} mm RMS "
                             f"(> {max_rms_m * 1000:.0f} mm): misdetected or moved marker", n, rms, aniso)
    return HomographyFit(H, True, "", n, rms, aniso)


def camera_centre_from_homography(H: np.ndarray, K: np.ndarray) -> np.ndarray | None:
    """Camera centre (3,) in the arena frame (z = height above the reference plane) from the
    floor homography H (undistorted px → m) and intrinsics K: ``K⁻¹H⁻¹ = λ[r1 r2 t]``
    (Zhang's plane-based decomposition), R orthonormalised by SVD, ``C = −Rᵀt``. None when
    degenerate."""
    M = np.linalg.solve(K, np.linalg.inv(H))
    n1, n2 = np.linalg.norm(M[:, 0]), np.linalg.norm(M[:, 1])
    if not (np.isfinite(n1) and np.isfinite(n2)) or n1 < 1e-12 or n2 < 1e-12:
        return None
    M = M / np.sqrt(n1 * n2)
    if M[2, 2] < 0:                     # the plane must lie in front of the camera
        M = -M
    r1, r2, t = M[:, 0], M[:, 1], M[:, 2]
    U, _, Vt = np.linalg.svd(np.column_stack([r1, r2, np.cross(r1, r2)]))
    R = U @ Vt
    C = -R.T @ t
    if not np.all(np.isfinite(C)):
        return None
    return C if C[2] > 0 else None      # the camera must look down on the plane from above


def correct_parallax(points: np.ndarray, camera_centre: np.ndarray, height: float) -> np.ndarray:
    """Points (..., 2) found on the reference plane by the homography that really lie
    ``height`` m above it → their true (x, y): scale about the camera nadir by
    ``(Z − height) / Z`` where Z is the camera height above the reference plane
    (REFERENCE.md §7: displacement h·d/H)."""
    p = np.asarray(points, dtype=np.float64)
    C = np.asarray(camera_centre, dtype=np.float64)
    k = (C[2] - height) / C[2]
    return C[:2] + (p - C[:2]) * k
