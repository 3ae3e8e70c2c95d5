"""The synthetic overhead camera: renders the arena as a webcam above it would see it.

Ray-traced per pixel through an exact pinhole model with lens distortion
(:mod:`swarmdeck.tracking.camera_model`): each pixel centre is undistorted once, intersected
with the floor (z = 0) and with the plane of the robot tags (z = ``tag_height``), and the
colour is looked up in pre-filtered textures (anti-aliased edges at sub-pixel positions). The
floor carries a grey mottled texture, the arena outline, the four reference markers and the
optional projected density image (the paper's overhead projector, Fig. 9); each robot is its
top — a dark disc of the robot's radius at tag height carrying a white plate with its
DICT_4X4_50 tag (the disc's side walls are not drawn). Then blur, vignetting, Gaussian noise
and JPEG compression. Ground truth (poses, projected tag corners) is exact.
"""
from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import cv2
import numpy as np

from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds
from swarmdeck.core.constants import ROBOT_RADIUS
from swarmdeck.tracking.calibration import CharucoSpec
from swarmdeck.tracking.camera_model import PinholeCamera, overhead_camera
from swarmdeck.tracking.dictionaries import dictionary
from swarmdeck.tracking.markers import DEFAULT_REFERENCES, ReferenceMarker, marker_corners
from swarmdeck.tracking.raster import disc_coverage, marker_image, pixel_edge_square, warp_into
from swarmdeck.tracking.types import CameraFrame


@dataclass(frozen=True)
class SyntheticCameraConfig:
    """Scene, camera pose and image degradations of the synthetic camera.

    Camera: ``camera_height`` m above the floor, optical axis ``tilt`` rad from vertical
    towards ``tilt_azimuth`` (keystone), ``roll`` rad about the axis, aimed at ``look_at``;
    focal length fitted so ``view_bounds`` fills the frame unless ``focal_px`` is given.
    ``distortion`` is OpenCV's (k1, k2, p1, p2, k3). Robots: ``tag_size`` m tags, white plate
    ``plate_scale``×tag, on a disc of ``body_radius`` m at ``tag_height`` m. Degradations:
    Gaussian blur ``blur_sigma`` px, noise ``noise_sigma`` grey levels, JPEG ``jpeg_quality``
    (None: off), ``vignetting`` (fractional darkening at the corners). A projector's image (``render``'s
    ``projection``) lights floor and robots: a pixel's brightness is scaled by ``1 − k + k·light`` with
    ``k = projection_strength`` (the projector's share of the light: low under strong ambient light).
    """

    width: int = 1280
    height: int = 720
    camera_height: float = 2.6
    tilt: float = 0.10
    tilt_azimuth: float = np.pi / 2
    roll: float = 0.01
    look_at: tuple[float, float] = (0.0, 0.0)
    view_bounds: tuple[float, float, float, float] = (-1.8, 1.8, -1.2, 1.2)
    focal_px: float | None = None
    distortion: tuple[float, ...] = (-0.10, 0.03, 0.0004, -0.0003, 0.0)
    dictionary: str = "DICT_4X4_50"
    references: tuple[ReferenceMarker, ...] = DEFAULT_REFERENCES
    bounds: Bounds = DEFAULT_BOUNDS
    tag_size: float = 0.08
    plate_scale: float = 1.3
    tag_height: float = 0.06
    body_radius: float = ROBOT_RADIUS
    body_rgb: tuple[int, int, int] = (40, 44, 52)
    floor_texel: float = 0.002
    sprite_texel: float = 0.0005
    blur_sigma: float = 0.6
    noise_sigma: float = 3.0
    jpeg_quality: int | None = 85
    vignetting: float = 0.15
    density_strength: float = 0.6
    projection_strength: float = 0.7
    seed: int = 0

    def camera(self) -> PinholeCamera:
        """The pinhole model of this configuration."""
        return overhead_camera(
            (self.width, self.height), self.camera_height, self.tilt, self.tilt_azimuth,
            self.roll, self.look_at, self.view_bounds, np.array(self.distortion), self.focal_px)


@dataclass(frozen=True, eq=False)
class SyntheticFrame:
    """A rendered frame with its exact truth: ids (N,), poses (N, 3), tag corners in distorted
    pixels (N, 4, 2) and the reference corners in pixels (R, 4, 2)."""

    image: np.ndarray
    ids: np.ndarray
    poses: np.ndarray
    tag_corners_px: np.ndarray
    reference_corners_px: np.ndarray
    visible: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))


def _apply_h(H: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """Apply a 3×3 homography to (..., 2) points."""
    shp = pts.shape
    out = cv2.perspectiveTransform(pts.reshape(-1, 1, 2).astype(np.float64), H)
    return out.reshape(shp)


class SyntheticRenderer:
    """Renders frames for one fixed :class:`SyntheticCameraConfig` (the per-pixel geometry,
    floor image and robot sprites are computed once here)."""

    def __init__(self, config: SyntheticCameraConfig = SyntheticCameraConfig()) -> None:
        self.config = config
        self.camera = config.camera()
        cam = self.camera
        grid = cam.normalised_pixel_grid()
        self._floor_xy = _apply_h(np.linalg.inv(cam.plane_homography(0.0)), grid).astype(np.float32)
        self._top_xy = _apply_h(np.linalg.inv(cam.plane_homography(config.tag_height)), grid).astype(np.float32)
        step = np.linalg.norm(np.diff(self._floor_xy, axis=1), axis=-1)
        self._floor_footprint = float(np.median(step))
        top_step = np.linalg.norm(np.diff(self._top_xy, axis=1), axis=-1)
        self._top_footprint = float(np.median(top_step))
        w, h = cam.size
        u, v = np.meshgrid((np.arange(w) - (w - 1) / 2) / (w / 2), (np.arange(h) - (h - 1) / 2) / (h / 2))
        self._gain = (1.0 - config.vignetting * 0.5 * (u ** 2 + v ** 2)).astype(np.float32)[..., None]
        # static floor with vignetting and the camera blur applied once; the robot sprites get
        # the same blur folded into their pre-filter, so no full-frame blur is needed per frame
        base = self._render_floor() * self._gain
        self._base = cv2.GaussianBlur(base, (0, 0), config.blur_sigma) if config.blur_sigma > 0 else base
        self._atlas, self._slot_of, self._sprite_side = self._build_sprites()
        extent = self._sprite_side * config.sprite_texel / 2
        self._window = int(np.ceil(2 * extent / float(top_step.min()))) + 3
        self._density_maps: dict[tuple[int, int], tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        self._projection_map: tuple[tuple[bytes, tuple[int, ...]], np.ndarray, np.ndarray] | None = None
        pad = 32
        self._noise = (np.random.default_rng(config.seed + 7).standard_normal((h + pad, w + pad, 3), dtype=np.float32)
                       * np.float32(config.noise_sigma)) if config.noise_sigma > 0 else None

    # -- static layers ---------------------------------------------------------------------
    def _render_floor(self) -> np.ndarray:
        """(h, w, 3) float32 floor as seen by the camera (texture, outline, references)."""
        cfg = self.config
        rng = np.random.default_rng(cfg.seed)
        fx, fy = self._floor_xy[..., 0], self._floor_xy[..., 1]
        pad = 0.05
        x0, x1 = max(float(fx.min()) - pad, -8.0), min(float(fx.max()) + pad, 8.0)
        y0, y1 = max(float(fy.min()) - pad, -8.0), min(float(fy.max()) + pad, 8.0)
        tx = cfg.floor_texel
        tw, th = int(np.ceil((x1 - x0) / tx)) + 1, int(np.ceil((y1 - y0) / tx)) + 1
        # texel (c, r) ↔ (x0 + c·tx, y1 − r·tx)
        coarse = rng.normal(0.0, 1.0, (max(th // 80, 2), max(tw // 80, 2))).astype(np.float32)
        mottle = cv2.resize(coarse, (tw, th), interpolation=cv2.INTER_CUBIC)
        fine = rng.standard_normal((th // 2 + 1, tw // 2 + 1), dtype=np.float32)
        grain = cv2.resize(fine, (tw, th), interpolation=cv2.INTER_LINEAR)
        grey = 150.0 + 10.0 * mottle + 5.0 * grain
        tex = grey[..., None] * np.array([1.0, 0.98, 0.94], np.float32)

        def to_tex(p: np.ndarray) -> np.ndarray:
            return np.column_stack([(p[:, 0] - x0) / tx, (y1 - p[:, 1]) / tx])

        bx0, bx1, by0, by1 = cfg.bounds
        outline = to_tex(np.array([[bx0, by1], [bx1, by1], [bx1, by0], [bx0, by0]]))
        cv2.polylines(tex, [np.round(outline * 16).astype(np.int32)], True, (70.0, 70.0, 75.0),
                      thickness=max(int(round(0.01 / tx)), 1), lineType=cv2.LINE_AA, shift=4)
        for ref in cfg.references:
            plate = marker_corners(np.array([[ref.x, ref.y]]), np.array([ref.heading]), ref.size * 1.4)[0]
            white = np.full((8, 8, 3), 245.0, np.float32)
            warp_into(tex, white, pixel_edge_square(8), to_tex(plate))
            img = marker_image(cfg.dictionary, ref.id)
            rgb = np.repeat(img[..., None], 3, axis=2).astype(np.float32) * (235.0 / 255.0) + 10.0
            warp_into(tex, rgb, pixel_edge_square(img.shape[0]), to_tex(ref.corners()))
        sigma = 0.4 * self._floor_footprint / tx
        if sigma > 0.3:
            tex = cv2.GaussianBlur(tex, (0, 0), sigma)
        mx = (self._floor_xy[..., 0] - x0) / tx
        my = (y1 - self._floor_xy[..., 1]) / tx
        return cv2.remap(tex, mx.astype(np.float32), my.astype(np.float32), cv2.INTER_LINEAR,
                         borderMode=cv2.BORDER_REPLICATE)

    def _build_sprites(self) -> tuple[np.ndarray, dict[int, int], int]:
        """RGBA atlas (float32) of robot tops, one sprite per dictionary id, in robot-local
        coordinates: sprite texel (c, r) ↔ local (x, y) = ((c − c0)·s, (c0 − r)·s)."""
        cfg = self.config
        s = cfg.sprite_texel
        plate_half = cfg.tag_size * cfg.plate_scale / 2
        extent = max(cfg.body_radius, plate_half * np.sqrt(2)) + 0.004
        side = int(np.ceil(2 * extent / s)) | 1
        c0 = (side - 1) / 2
        yy, xx = np.mgrid[0:side, 0:side].astype(np.float32)
        r = np.hypot(xx - c0, yy - c0)
        body_a = disc_coverage(r, cfg.body_radius / s)
        ph = plate_half / s
        plate_a = np.clip(ph - np.abs(xx - c0) + 0.5, 0, 1) * np.clip(ph - np.abs(yy - c0) + 0.5, 0, 1)
        base = np.zeros((side, side, 4), np.float32)
        base[..., :3] = np.array(cfg.body_rgb, np.float32)
        base[..., :3] = base[..., :3] * (1 - plate_a[..., None]) + 245.0 * plate_a[..., None]
        base[..., 3] = np.maximum(body_a, plate_a) * 255.0
        n_ids = dictionary(cfg.dictionary).bytesList.shape[0]
        cols = 8
        rows = int(np.ceil(n_ids / cols))
        atlas = np.zeros((rows * side, cols * side, 4), np.float32)
        self._cols = cols
        self._sprite_base = base
        self._n_ids = n_ids
        return atlas, {}, side

    def _ensure_sprites(self, ids: np.ndarray) -> None:
        """Draw the sprites of ``ids`` into the atlas the first time they are needed."""
        cfg = self.config
        todo = [int(k) for k in np.unique(ids) if 0 <= k < self._n_ids and int(k) not in self._slot_of]
        if not todo:
            return
        s, side = cfg.sprite_texel, self._sprite_side
        c0 = (side - 1) / 2
        tag_px = marker_corners(np.zeros((1, 2)), np.zeros(1), cfg.tag_size)[0] / s
        tag_tex = np.column_stack([c0 + tag_px[:, 0], c0 - tag_px[:, 1]])
        sigma = float(np.hypot(0.4, cfg.blur_sigma)) * self._top_footprint / s
        for k in todo:
            sp = self._sprite_base.copy()
            img = marker_image(cfg.dictionary, k)
            rgb = np.repeat(img[..., None], 3, axis=2).astype(np.float32) * (235.0 / 255.0) + 10.0
            color = sp[..., :3].copy()
            warp_into(color, rgb, pixel_edge_square(img.shape[0]), tag_tex)
            sp[..., :3] = color
            if sigma > 0.3:
                sp = cv2.GaussianBlur(sp, (0, 0), sigma)  # type: ignore[assignment]  # cv2's stubs
            # premultiply colour by alpha so bilinear lookups at the rim stay unbiased
            sp[..., :3] *= sp[..., 3:4] / 255.0
            rr, cc = divmod(k, self._cols)
            self._atlas[rr * side:(rr + 1) * side, cc * side:(cc + 1) * side] = sp
            self._slot_of[k] = k

    # -- per-frame layers ------------------------------------------------------------------
    def _density_layer(self, img: np.ndarray, out: np.ndarray) -> None:
        """Project an (dh, dw[, 3]) image covering ``bounds`` onto the floor (in place)."""
        a = np.asarray(img)
        if a.ndim == 2:
            a = np.repeat(a[..., None], 3, axis=2)
        if a.dtype != np.uint8:
            a = np.clip(a * 255.0 if a.max() <= 1.0 else a, 0, 255).astype(np.uint8)
        dh, dw = a.shape[:2]
        key = (dh, dw)
        if key not in self._density_maps:
            bx0, bx1, by0, by1 = self.config.bounds
            mx = (self._floor_xy[..., 0] - bx0) / (bx1 - bx0) * dw - 0.5
            my = (by1 - self._floor_xy[..., 1]) / (by1 - by0) * dh - 0.5
            inside = ((mx > -0.5) & (mx < dw - 0.5) & (my > -0.5) & (my < dh - 0.5)).astype(np.float32)
            self._density_maps[key] = (mx.astype(np.float32), my.astype(np.float32), inside[..., None])
        mx, my, inside = self._density_maps[key]
        proj = cv2.remap(a, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE).astype(np.float32)
        k = self.config.density_strength * inside
        out *= (1.0 - k) + k * proj / 255.0

    def _robot_layer(self, ids: np.ndarray, poses: np.ndarray, out: np.ndarray) -> np.ndarray:
        """Composite the robot tops into ``out`` (in place); returns (N,) bool visible."""
        cfg = self.config
        n = len(ids)
        if n == 0:
            return np.zeros(0, bool)
        self._ensure_sprites(ids)
        h, w = out.shape[:2]
        centres = np.column_stack([poses[:, :2], np.full(n, cfg.tag_height)])
        px = self.camera.project(centres)
        visible = (px[:, 0] > -self._window) & (px[:, 0] < w + self._window) & \
                  (px[:, 1] > -self._window) & (px[:, 1] < h + self._window)
        W = self._window
        off = np.arange(W) - W // 2
        u = np.round(px[:, 0]).astype(int)[:, None, None] + off[None, None, :]
        v = np.round(px[:, 1]).astype(int)[:, None, None] + off[None, :, None]
        u, v = np.broadcast_to(u, (n, W, W)), np.broadcast_to(v, (n, W, W))
        valid = (u >= 0) & (u < w) & (v >= 0) & (v < h) & visible[:, None, None]
        uc, vc = np.clip(u, 0, w - 1), np.clip(v, 0, h - 1)
        P = self._top_xy[vc, uc]                                   # (n, W, W, 2)
        d = P - poses[:, None, None, :2].astype(np.float32)
        c = np.cos(poses[:, 2]).astype(np.float32)[:, None, None]
        s = np.sin(poses[:, 2]).astype(np.float32)[:, None, None]
        lx = c * d[..., 0] + s * d[..., 1]
        ly = -s * d[..., 0] + c * d[..., 1]
        side = self._sprite_side
        c0 = (side - 1) / 2
        slot = np.where((ids >= 0) & (ids < self._n_ids), ids, -1)
        valid &= (slot >= 0)[:, None, None]
        rr, cc = np.divmod(np.maximum(slot, 0), self._cols)
        tx = cfg.sprite_texel
        mx = (cc * side + c0)[:, None, None] + lx / tx
        my = (rr * side + c0)[:, None, None] - ly / tx
        inside = (np.abs(lx) < c0 * tx) & (np.abs(ly) < c0 * tx) & valid
        samp = cv2.remap(self._atlas, mx.reshape(n * W, W).astype(np.float32),
                         my.reshape(n * W, W).astype(np.float32), cv2.INTER_LINEAR,
                         borderMode=cv2.BORDER_CONSTANT, borderValue=0).reshape(n, W, W, 4)
        alpha = samp[..., 3] / 255.0 * inside
        flat = (vc * w + uc)[inside]
        a = alpha[inside]
        col = samp[..., :3][inside]
        idx, inv = np.unique(flat, return_inverse=True)
        sum_a = np.bincount(inv, weights=a, minlength=len(idx))
        outf = out.reshape(-1, 3)
        keep = np.clip(1.0 - sum_a, 0.0, 1.0)
        premult = np.stack([np.bincount(inv, weights=col[:, k], minlength=len(idx)) for k in range(3)], axis=1)
        gain = self._gain.reshape(-1)[idx]
        outf[idx] = outf[idx] * keep[:, None] + premult * gain[:, None]
        return visible

    def _projection_layer(self, image: np.ndarray, H: np.ndarray, out: np.ndarray) -> None:
        """Light the scene with a projector's image (ph, pw[, 3]) uint8 through H (floor m → projector px),
        in place: floor and robot tops alike (the tops through the floor's mapping: the few-mm parallax of
        the tag height is ignored); black outside the projector's image."""
        a = np.asarray(image)
        if a.ndim == 2:
            a = np.repeat(a[..., None], 3, axis=2)
        key = (np.asarray(H, np.float64).tobytes(), a.shape[:2])
        cached = self._projection_map
        if cached is None or cached[0] != key:
            uv = _apply_h(np.asarray(H, np.float64), self._floor_xy.astype(np.float64)).astype(np.float32)
            cached = (key, np.ascontiguousarray(uv[..., 0]), np.ascontiguousarray(uv[..., 1]))
            self._projection_map = cached
        _, mu, mv = cached
        light = cv2.remap(np.ascontiguousarray(a, dtype=np.uint8), mu, mv, cv2.INTER_LINEAR,
                          borderMode=cv2.BORDER_CONSTANT, borderValue=(0, 0, 0)).astype(np.float32)
        k = np.float32(self.config.projection_strength)
        out *= (np.float32(1.0) - k) + light * (k / np.float32(255.0))

    # -- public ----------------------------------------------------------------------------
    def render(self, ids: Sequence[int] | np.ndarray, poses: np.ndarray, density: np.ndarray | None = None,
               rng: np.random.Generator | None = None,
               projection: tuple[np.ndarray, np.ndarray] | None = None) -> SyntheticFrame:
        """Render robots ``ids`` (N,) at ``poses`` (N, 3) (and a density image covering the
        arena bounds, optional; a projector's ``(image, H floor m → projector px)``, optional)
        → :class:`SyntheticFrame` (RGB uint8 image + exact truth)."""
        cfg = self.config
        ids = np.asarray(ids, dtype=int).reshape(-1)
        poses = np.asarray(poses, dtype=float).reshape(-1, 3)
        if len(ids) != len(poses):
            raise ValueError(f"ids ({len(ids)},) and poses {poses.shape} disagree in length")
        rng = rng if rng is not None else np.random.default_rng(cfg.seed)
        out = self._base.copy()
        if density is not None:
            self._density_layer(density, out)
        visible = self._robot_layer(ids, poses, out)
        if projection is not None:
            self._projection_layer(projection[0], projection[1], out)
        h, w = out.shape[:2]
        if self._noise is not None:          # a random window of a fixed Gaussian noise field
            dy, dx = rng.integers(0, self._noise.shape[0] - h + 1), rng.integers(0, self._noise.shape[1] - w + 1)
            out += self._noise[dy:dy + h, dx:dx + w]
        out += np.float32(0.5)
        np.clip(out, 0, 255, out=out)
        img = out.astype(np.uint8)
        if cfg.jpeg_quality is not None:
            ok, buf = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, int(cfg.jpeg_quality)])
            if ok:
                img = cv2.imdecode(buf, cv2.IMREAD_COLOR)
        tag_c = marker_corners(poses[:, :2], poses[:, 2], cfg.tag_size)
        tag_px = self.camera.project(np.concatenate(
            [tag_c, np.full(tag_c.shape[:2] + (1,), cfg.tag_height)], axis=2).reshape(-1, 3)).reshape(-1, 4, 2)
        ref_c = np.array([r.corners() for r in cfg.references]).reshape(-1, 4, 2)
        ref_px = self.camera.project(np.concatenate(
            [ref_c, np.zeros(ref_c.shape[:2] + (1,))], axis=2).reshape(-1, 3)).reshape(-1, 4, 2)
        return SyntheticFrame(image=img, ids=ids, poses=poses.copy(), tag_corners_px=tag_px,
                              reference_corners_px=ref_px, visible=visible)


PoseCallable = Callable[[float], np.ndarray]


class SyntheticCamera:
    """A camera source that renders whatever ``get_poses(now)`` returns.

    ``get_poses(now) -> (N, 3)`` poses (robot ids ``ids``, default 0..N−1), e.g. the simulator's
    truth: ``SyntheticCamera(lambda t: sim.poses(), ids=range(n))``. ``get_density(now)`` may
    return an image covering the arena bounds to project onto the floor. Each ``read(now)``
    renders one frame stamped ``now`` (the virtual clock of the loop); ``last`` holds the truth
    of the newest frame. Exceptions from the callables become a status message, not a crash.
    """

    def __init__(self, get_poses: PoseCallable, ids: Sequence[int] | None = None,
                 config: SyntheticCameraConfig = SyntheticCameraConfig(),
                 get_density: Callable[[float], np.ndarray | None] | None = None,
                 renderer: SyntheticRenderer | None = None) -> None:
        self.renderer = renderer if renderer is not None else SyntheticRenderer(config)
        self.config = self.renderer.config
        self._get_poses = get_poses
        self._get_density = get_density
        self._ids = None if ids is None else np.asarray(list(ids), dtype=int)
        self._rng = np.random.default_rng(self.config.seed + 1)
        self._index = 0
        self.last: SyntheticFrame | None = None
        self.status = "synthetic camera ready"
        self.render_time_s = float("nan")

    @property
    def ok(self) -> bool:
        """True when the last read produced a frame."""
        return self.status.startswith("synthetic camera") and "error" not in self.status

    def read(self, now: float) -> CameraFrame | None:
        """Render the scene at ``now`` → a new frame stamped ``now`` (None on error)."""
        t0 = time.perf_counter()
        try:
            poses = np.asarray(self._get_poses(now), dtype=float)
            if poses.ndim != 2 or poses.shape[1] != 3 or not np.all(np.isfinite(poses)):
                raise ValueError(f"get_poses returned shape {poses.shape}, expected finite (N, 3) poses")
            ids = self._ids if self._ids is not None else np.arange(len(poses))
            if len(ids) != len(poses):
                raise ValueError(f"{len(poses)} poses for {len(ids)} ids")
            density = self._get_density(now) if self._get_density is not None else None
            frame = self.renderer.render(ids, poses, density, self._rng)
        except Exception as exc:  # noqa: BLE001 - user callables must not kill the loop
            self.status = f"synthetic camera error: {type(exc).__name__}: {exc}"
            return None
        self.last = frame
        self.render_time_s = time.perf_counter() - t0
        self.status = f"synthetic camera {self.config.width}×{self.config.height}"
        out = CameraFrame(image=frame.image, stamp=float(now), index=self._index, wall=time.monotonic())
        self._index += 1
        return out

    def close(self) -> None:
        """Nothing to release."""
        self.status = "synthetic camera closed"


def random_poses(n: int, rng: np.random.Generator, bounds: Bounds = DEFAULT_BOUNDS,
                 min_distance: float = 0.2, margin: float = 0.1, max_tries: int = 200) -> np.ndarray:
    """(n, 3) random poses inside ``bounds`` (shrunk by ``margin``) with centres at least
    ``min_distance`` apart (dart throwing; raises ValueError when they do not fit)."""
    x0, x1, y0, y1 = bounds
    out = np.zeros((0, 2))
    for _ in range(max_tries):
        if len(out) >= n:
            break
        cand = np.column_stack([rng.uniform(x0 + margin, x1 - margin, 4 * n),
                                rng.uniform(y0 + margin, y1 - margin, 4 * n)])
        for p in cand:
            if len(out) >= n:
                break
            if len(out) == 0 or np.min(np.hypot(*(out - p).T)) >= min_distance:
                out = np.vstack([out, p])
    if len(out) < n:
        raise ValueError(f"cannot place {n} robots {min_distance} m apart in {bounds}")
    return np.column_stack([out, rng.uniform(-np.pi, np.pi, n)])


def charuco_views(camera: PinholeCamera, spec: CharucoSpec, n_views: int, rng: np.random.Generator,
                  blur_sigma: float = 0.6, noise_sigma: float = 2.0) -> list[np.ndarray]:
    """``n_views`` RGB images of a ChArUco board held in front of ``camera`` (its intrinsics and
    distortion; extrinsics ignored) at random distances, tilts and image positions — input for
    a calibration round trip. Board texture from OpenCV's own ``generateImage``, whose pixel
    edges coincide with the board's object-point coordinates."""
    ppsq = 100
    tex = spec.board().generateImage((spec.squares_x * ppsq, spec.squares_y * ppsq), marginSize=0, borderBits=1)
    texel = spec.square_length / ppsq
    bw, bh = spec.squares_x * spec.square_length, spec.squares_y * spec.square_length
    grid = camera.normalised_pixel_grid()
    w, h = camera.size
    f = camera.K[0, 0]
    tex_blurred: dict[int, np.ndarray] = {}
    views = []
    for _ in range(n_views):
        depth = rng.uniform(0.8, 1.6) * f * bw / (0.45 * w)          # board ≈ 30–55 % of the width
        ax, ay, az = rng.uniform(-0.6, 0.6), rng.uniform(-0.6, 0.6), rng.uniform(-0.4, 0.4)
        R, _ = cv2.Rodrigues(np.array([ax, ay, az]))
        target = np.array([rng.uniform(0.15, 0.85) * w, rng.uniform(0.15, 0.85) * h])
        ray = np.linalg.solve(camera.K, np.array([*target, 1.0]))
        centre_c = ray / ray[2] * depth
        t = centre_c - R @ np.array([bw / 2, bh / 2, 0.0])
        Hplane = np.column_stack([R[:, 0], R[:, 1], t])              # board (x, y, 1) → normalised
        xy = _apply_h(np.linalg.inv(Hplane), grid)
        footprint = depth / f / max(abs(R[2, 2]), 0.3)
        sig = int(round(max(0.4 * footprint / texel, 0.0) * 4))
        if sig not in tex_blurred:
            tex_blurred[sig] = cv2.GaussianBlur(tex.astype(np.float32), (0, 0), sig / 4) if sig > 1 else tex.astype(np.float32)
        mx = (xy[..., 0] / texel - 0.5).astype(np.float32)
        my = (xy[..., 1] / texel - 0.5).astype(np.float32)
        img = cv2.remap(tex_blurred[sig], mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=120.0)
        # pixels whose ray meets the plane behind the camera see background
        behind = (Hplane @ np.array([bw / 2, bh / 2, 1.0]))[2] <= 0
        if behind:
            img[:] = 120.0
        if blur_sigma > 0:
            img = cv2.GaussianBlur(img, (0, 0), blur_sigma)
        img = img + rng.standard_normal(img.shape, dtype=np.float32) * np.float32(noise_sigma)
        g = np.clip(img + 0.5, 0, 255).astype(np.uint8)
        views.append(cv2.cvtColor(g, cv2.COLOR_GRAY2RGB))
    return views


def density_image(evaluate: Callable[[np.ndarray], np.ndarray],
                  bounds: Bounds = DEFAULT_BOUNDS,
                  shape: tuple[int, int] = (100, 160), rgb: tuple[int, int, int] = (255, 120, 20)) -> np.ndarray:
    """Rasterise a density for the synthetic projector: ``evaluate(q (M, 2)) -> φ (M,)`` (e.g.
    ``GaussianMixture.evaluate``) on a ``shape`` (rows, cols) grid of pixel centres over
    ``bounds`` (row 0 at y_max) → (rows, cols, 3) uint8, white where φ is smallest and ``rgb``
    where it is largest (φ normalised by its range on the grid)."""
    rows, cols = shape
    b = Bounds.of(bounds)
    xs = b.x_min + (np.arange(cols) + 0.5) * b.width / cols
    ys = b.y_max - (np.arange(rows) + 0.5) * b.height / rows
    X, Y = np.meshgrid(xs, ys)
    phi = np.asarray(evaluate(np.column_stack([X.ravel(), Y.ravel()])), dtype=float).reshape(rows, cols)
    lo, hi = np.nanmin(phi), np.nanmax(phi)
    t = np.zeros_like(phi) if not hi > lo else np.clip((phi - lo) / (hi - lo), 0.0, 1.0)
    t = np.nan_to_num(t)[..., None]
    out = 255.0 * (1 - t) + np.asarray(rgb, float) * t
    return np.clip(out + 0.5, 0, 255).astype(np.uint8)
