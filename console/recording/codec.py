"""Recording messages ⇄ bytes: the one place that knows how each swarmdeck channel is written.

``encode_frame(frame) -> bytes`` is what the recorder writes on ``/swarmdeck/frame``;
``decode_frame(data) -> Frame`` reads it back, for every frame format ever written.
Other writers (Foxglove channels, exports, recovery tools) call these two. The other channels
(``schemas.py`` lists them) are here too: :func:`datagram_message` / :func:`decode_datagram`
(``/swarmdeck/datagram``), :func:`event_message` / :func:`decode_event` (``/swarmdeck/event``),
:func:`decode_config` (``/swarmdeck/config``) and :func:`metadata_record` / :func:`decode_metadata`
(the ``swarmdeck`` metadata record: every value JSON-encoded). The Foxglove channels' own
messages are :mod:`swarmdeck.console.recording.foxglove`'s.

Frame format 2 (recording format 2) — compact
---------------------------------------------
A JSON object (message encoding ``json``), :meth:`Frame.to_dict`'s layout with
``"format": 2`` and these changes:

* per-robot arrays are **binary**: an object ``{"nd": dtype, "shape": [...],
  "b64": base64}`` where dtype is a little-endian numpy type string (``"<f8"``,
  ``"<f4"``, ``"<i8"``, ``"|b1"``) and the bytes are the array's little-endian
  bytes *byte-shuffled* (all bytes 0 of every element, then all bytes 1, …: the
  high bytes of similar numbers sit together and compress well). Read with
  ``np.frombuffer(b, "u1").reshape(itemsize, -1).T.copy().view(dtype).reshape(shape)``.
* exact float64 (bit for bit): ``poses``, ``v``, ``w`` — what re-simulation and
  replay need; everything else is for display and is compared at the precision below.
* derived on reading instead of stored: ``safe`` = ṗ = M(θ)[v, ω] (REFERENCE.md §1:
  the look-ahead velocity of the command sent) and the coverage geometry (``edges``, ``neighbours``, cells) —
  the bounded Voronoi diagram of the look-ahead points and its cell moments under the
  frame's density snapshot, recomputed from the poses when ``coverage.geometry`` is
  ``"derived"`` by the function the live tick runs (``swarmdeck.coverage.coverage_geometry``)
  with the frame's coverage config: ``coverage.config``, the fields of
  ``GeometryConfig`` that differ from its defaults on the frame's bounds, absent when none
  does (and in every file written before it was stored); the centroids and masses are
  stored as float64 only when there is no diagram; and ``barrier.active_h`` = ‖p_i − p_j‖² − D_s² of the ``active_pairs``
  (int16, int32 beyond 32 767 robots). ``nominal`` is stored as float16
  ``nominal_minus_safe`` (zero where neither the wheel limits nor the barrier changed
  the command; error ≤ 5e-4 of that difference), ``barrier.intervention`` float16.
  ``timing`` is rounded to 1 µs.
* ``sensors`` (what the robots sensed), only when present: :class:`SensorsFrame`'s packed form (distances and
  IMU float32, LEDs uint8, encoders int32; the rays are derived from the poses on drawing).
* the fleet's per-robot state, each only when it says something (as in
  :meth:`Frame.fleet_dict`; absent in older recordings, which read as all physical,
  battery unknown, not charging): ``is_virtual`` bool, ``battery`` float32 V, ``charging`` bool.

Frame format 3 (recording format 3) — format 2, predicted from the previous frame
---------------------------------------------------------------------------------
A format-2 message with ``"format": 3``, of one of two kinds:

* a **keyframe** (no ``"pred"`` key): self-contained, exactly a format-2 message otherwise.
* a **predicted frame**: ``"pred": {"ref": tick, "crc": crc32}`` — coded against the frame of
  tick ``ref``, the one written just before it *in the same MCAP chunk*. Its exact fields
  ``ids``, ``poses``, ``v``, ``w`` are ``"<u8"`` arrays (shapes unchanged) of residuals
  r = zigzag(bits(x) − bits(x̂)): the little-endian IEEE-754 (two's complement for ids) bit
  patterns as 64-bit integers, subtracted modulo 2⁶⁴, zigzagged (0, −1, 1, −2, … → 0, 1, 2,
  3, …) so that a prediction off by a few ulps leaves only low bytes. The prediction x̂ of the
  poses is the reference frame's poses moved by its (v, ω) over its ``dt``
  (:func:`~swarmdeck.console.recording.prediction.predict_poses`: the simulator's unicycle
  step in machine-independent arithmetic, so a simulated robot's residual is zero in all but
  a few percent of the headings, a tracked robot's its measurement noise); of ``ids``, ``v``
  and ``w`` the reference frame's values. The byte-shuffled planes of such residuals are almost
  all zero bytes and compress to almost nothing in the chunk's zstd. ``crc`` is the CRC-32
  (``zlib.crc32``) of the little-endian bytes of ``ids`` (int64), ``poses``, ``v``, ``w``
  (float64) in that order: the decoder checks the bits it reconstructs. Everything else is as in
  format 2 (and derived on reading from the reconstructed poses).

The recorder writes a keyframe as the first frame of every chunk (it closes chunks itself:
every ``chunk_frames`` frames, before ``chunk_size`` bytes, and after ``flush_interval`` s without input) and after
any gap (a tick that does not follow the previous frame's, a change in the robot count, a time
that does not increase, a frame that could not be written); so every chunk decodes on its
own, and seeking, recovery of a cut-off file and re-simulation never need an earlier chunk.
:func:`decode_frame` takes the previous frame of the chunk (``previous=``) for a predicted
frame and raises :class:`MissingReference` without it.

Frame format 1 (recording format 1): ``Frame.to_dict()`` as plain JSON, every
float with 17 digits; still read.
"""
from __future__ import annotations

import base64
import json
import zlib
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from swarmdeck.console.recording.prediction import predict_poses
from swarmdeck.console.runtime.frame import (
    FRAME_FORMAT,
    BarrierFrame,
    CoverageFrame,
    Frame,
    _dec_float,
    _enc_float,
    filled,
)
from swarmdeck.console.runtime.sensors_frame import SensorsFrame
from swarmdeck.core.bounds import Bounds
from swarmdeck.core.errors import SwarmdeckError
from swarmdeck.core.kinematics import lookahead_points, unicycle_to_si
from swarmdeck.coverage.geometry import CoverageGeometry, GeometryConfig, coverage_geometry

#: The frame format this module writes (``Frame.to_dict`` is format 1; format 2: keyframes only).
CODEC_FORMAT = 3
#: Frame format 2 (compact, every frame self-contained): still read.
COMPACT_FORMAT = 2
#: Frame formats :func:`decode_frame` reads.
READABLE_FORMATS = (FRAME_FORMAT, COMPACT_FORMAT, CODEC_FORMAT)
#: The exact per-robot fields of a frame with their little-endian types; a predicted frame
#: stores them as residuals against the previous frame (module docstring).
EXACT_FIELDS = (("ids", "<i8"), ("poses", "<f8"), ("v", "<f8"), ("w", "<f8"))


def _json_codec() -> tuple[Any, Any]:
    try:
        import msgspec

        enc = msgspec.json.Encoder()
        dec = msgspec.json.Decoder()

        def loads(data: bytes) -> Any:
            try:
                return dec.decode(data)
            except msgspec.DecodeError as exc:
                raise ValueError(f"not JSON: {exc}") from None
        return enc.encode, loads
    except ImportError:  # pragma: no cover - msgspec comes with viser
        import json

        return (lambda obj: json.dumps(obj, separators=(",", ":"), allow_nan=False).encode("utf-8"),
                json.loads)


#: Compact strict JSON bytes of a JSON-able object; and its inverse (ValueError on bad JSON).
encode_json, decode_json = _json_codec()


# ---------------------------------------------------------------------------- binary arrays
def pack_array(a: np.ndarray, dtype: str) -> dict[str, Any]:
    """``{"nd", "shape", "b64"}``: ``a`` cast to the little-endian ``dtype``, byte-shuffled, base64."""
    arr = np.ascontiguousarray(a, dtype=np.dtype(dtype))
    size = arr.dtype.itemsize
    raw = arr.view(np.uint8).reshape(-1, size).T.tobytes() if size > 1 and arr.size else arr.tobytes()
    return {"nd": arr.dtype.str, "shape": list(arr.shape), "b64": base64.b64encode(raw).decode("ascii")}


def unpack_array(obj: Any, name: str) -> np.ndarray:
    """Inverse of :func:`pack_array`; ValueError naming ``name`` for malformed data."""
    if not isinstance(obj, Mapping) or not {"nd", "shape", "b64"} <= set(obj):
        raise ValueError(f"frame field {name!r} must be a binary array object {{nd, shape, b64}}")
    try:
        dt = np.dtype(str(obj["nd"]))
        shape = tuple(int(s) for s in obj["shape"])
        raw = base64.b64decode(obj["b64"], validate=True)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"frame field {name!r}: bad binary array: {exc}") from None
    if dt.kind not in "fiub" or dt.byteorder == ">":
        raise ValueError(f"frame field {name!r}: unsupported dtype {obj['nd']!r}")
    count = int(np.prod(shape))
    if len(raw) != count * dt.itemsize:
        raise ValueError(f"frame field {name!r}: {len(raw)} bytes for shape {shape} of {dt.str}")
    b = np.frombuffer(raw, dtype=np.uint8)
    if dt.itemsize > 1 and count:
        b = b.reshape(dt.itemsize, count).T
    return np.ascontiguousarray(b).view(dt).reshape(shape)


# ---------------------------------------------------------------------------- encode
def frame_message(frame: Frame, previous: Frame | None = None) -> dict[str, Any]:
    """The format-3 message of ``frame`` as a JSON-able dict (see the module docstring): a frame
    predicted from ``previous`` (the frame written just before it in the same chunk) when given
    and :func:`can_predict`, else a keyframe."""
    d = _scalars(frame)
    d["format"] = CODEC_FORMAT
    d["ids"] = pack_array(frame.ids, "<i8")
    d["poses"] = pack_array(frame.poses, "<f8")
    d["seen"] = pack_array(filled(frame.seen), "|b1")
    is_virtual, battery, charging = filled(frame.is_virtual), filled(frame.battery), filled(frame.charging)
    if is_virtual.any():
        d["is_virtual"] = pack_array(is_virtual, "|b1")
    if np.isfinite(battery).any():
        d["battery"] = pack_array(battery, "<f4")
    if charging.any():
        d["charging"] = pack_array(charging, "|b1")
    if frame.sensors is not None:  # written only when present (console/runtime/sensors_frame.py)
        d["sensors"] = frame.sensors.packed(pack_array)
    # nominal as float16 offsets from the derived safe command: zero where nothing changed it
    delta = frame.nominal - derived_safe(frame.poses, frame.v, frame.w, frame.lookahead)
    delta[np.abs(delta) < 1e-12] = 0.0
    d["nominal_minus_safe"] = pack_array(delta, "<f2")
    d["v"] = pack_array(frame.v, "<f8")
    d["w"] = pack_array(frame.w, "<f8")
    b = frame.barrier
    if b is not None:
        bd = _barrier_scalars(b)
        bd["active_pairs"] = pack_array(b.active_pairs, "<i2" if frame.n <= 32767 else "<i4")
        bd["intervention"] = pack_array(b.intervention, "<f2")
        d["barrier"] = bd
    c = frame.coverage
    if c is not None:
        derived = bool(len(c.cell_vertices)) and frame.density is not None
        cov: dict[str, Any] = {"cost_H": _enc_float(c.cost_H), "mean_centroid_distance": _enc_float(c.mean_centroid_distance),
               "packing_warning": c.packing_warning, "geometry": "derived" if derived else "none"}
        changes = c.geometry_config.changes(frame.bounds) if c.geometry_config is not None else {}
        if changes:  # a non-default coverage config: what the cells are derived with on reading
            cov["config"] = changes
        if not derived:  # no diagram to recompute (coverage failed this tick): store what there is
            cov["centroids"] = pack_array(c.centroids, "<f8")
            cov["masses"] = pack_array(c.masses, "<f8")
        d["coverage"] = cov
    if previous is not None and can_predict(frame, previous):
        d["pred"] = {"ref": int(previous.tick), "crc": exact_crc(frame.ids, frame.poses, frame.v, frame.w)}
        for name, dtype in EXACT_FIELDS:
            d[name] = pack_array(_zigzag(_bits(getattr(frame, name), dtype) - _predicted_bits(previous, name)), "<u8")
    return d


def encode_frame(frame: Frame, previous: Frame | None = None) -> bytes:
    """The bytes the recorder writes for ``frame`` (frame format 3, JSON with binary arrays): a
    keyframe, or with ``previous`` (the frame written just before it in the same chunk) a frame
    predicted from it."""
    return encode_json(frame_message(frame, previous))


def can_predict(frame: Frame, previous: Frame) -> bool:
    """True when ``frame`` can be coded against ``previous``: the next tick, a later time, the
    same number of robots."""
    return frame.tick == previous.tick + 1 and frame.time > previous.time and frame.n == previous.n


def exact_crc(ids: np.ndarray, poses: np.ndarray, v: np.ndarray, w: np.ndarray) -> int:
    """CRC-32 of the little-endian bytes of a frame's ids (int64), poses, v, w (float64), in that order."""
    crc = 0
    for a, (_, dtype) in zip((ids, poses, v, w), EXACT_FIELDS):
        crc = zlib.crc32(np.ascontiguousarray(a, dtype=np.dtype(dtype)).tobytes(), crc)
    return crc


def _bits(a: np.ndarray, dtype: str) -> np.ndarray:
    """The little-endian bit patterns of ``a`` as ``dtype`` (an 8-byte type), as uint64."""
    return np.ascontiguousarray(a, dtype=np.dtype(dtype)).view("<u8")


def _predicted_bits(previous: Frame, name: str) -> np.ndarray:
    """Bit patterns (uint64) of the prediction of field ``name`` from the previous frame: the poses
    moved by its (v, ω) over its dt, the other exact fields unchanged."""
    if name == "poses":
        return _bits(predict_poses(previous.poses, previous.v, previous.w, previous.dt), "<f8")
    return _bits(getattr(previous, name), dict(EXACT_FIELDS)[name])


def _zigzag(r: np.ndarray) -> np.ndarray:
    """uint64 residuals (two's complement) → zigzag: 0, −1, 1, −2, … → 0, 1, 2, 3, …"""
    s = r.view(np.int64)
    return ((s << np.int64(1)) ^ (s >> np.int64(63))).view(np.uint64)


def _unzigzag(z: np.ndarray) -> np.ndarray:
    """Inverse of :func:`_zigzag` (uint64)."""
    return (z >> np.uint64(1)) ^ (np.uint64(0) - (z & np.uint64(1)))


_BIG = ("ids", "poses", "seen", "nominal", "nominal_minus_safe", "safe", "v", "w", "barrier", "coverage",
        "is_virtual", "battery", "charging", "sensors")
_FLEET = (("is_virtual", bool), ("battery", float), ("charging", bool))


def active_h(poses: np.ndarray, pairs: np.ndarray, lookahead: float, safety_distance: float) -> np.ndarray:
    """Barrier values h = ‖p_i − p_j‖² − D_s² (m²) of robot pairs (K, 2) at their look-ahead points."""
    if not len(pairs):
        return np.zeros(0)
    p = lookahead_points(poses, lookahead)
    e = p[pairs[:, 0]] - p[pairs[:, 1]]
    d = np.sqrt(np.einsum("kd,kd->k", e, e))
    return d * d - safety_distance**2


def derived_safe(poses: np.ndarray, v: np.ndarray, w: np.ndarray, lookahead: float) -> np.ndarray:
    """The look-ahead point velocity (N, 2) m/s of the command sent: ṗ = M(θ)[v, ω] (REFERENCE.md §1)."""
    return unicycle_to_si(poses, v, w, lookahead) if len(poses) else np.zeros((0, 2))


def _scalars(frame: Frame) -> dict[str, Any]:
    """Frame.to_dict() without the per-robot arrays (those are packed by :func:`frame_message`)."""
    stripped = Frame(tick=frame.tick, time=frame.time, poses=np.empty((0, 3)), ids=np.empty(0, dtype=np.int64),
                     nominal=np.empty((0, 2)), safe=np.empty((0, 2)), v=np.empty(0), w=np.empty(0),
                     dt=frame.dt, run_time=frame.run_time, bounds=frame.bounds, lookahead=frame.lookahead,
                     density=frame.density, contacts=frame.contacts, behaviour=frame.behaviour,
                     run_state=frame.run_state, params=frame.params, events=frame.events, alerts=frame.alerts,
                     health=frame.health, timing=frame.timing, image_ref=frame.image_ref)
    d = stripped.to_dict()
    d["timing"] = {k: (round(v, 6) if isinstance(v, float) else v) for k, v in d["timing"].items()}
    for k in _BIG:
        d.pop(k, None)
    return d


def _barrier_scalars(b: BarrierFrame) -> dict[str, Any]:
    d = BarrierFrame(enabled=b.enabled, ok=b.ok, status=b.status, solve_time_s=b.solve_time_s,
                     n_constraints=b.n_constraints, n_active=b.n_active, min_distance=b.min_distance,
                     min_wall_clearance=b.min_wall_clearance, nominal_was_safe=b.nominal_was_safe,
                     safety_distance=b.safety_distance).to_dict()
    for k in ("active_pairs", "active_h", "intervention"):
        d.pop(k)  # packed binary by frame_message (active_h is derived on reading)
    return d


# ---------------------------------------------------------------------------- decode
class MissingReference(ValueError, SwarmdeckError):
    """A predicted frame (format 3) was read without the frame it is coded against."""


def decode_frame(data: bytes | Mapping[str, Any], previous: Frame | None = None) -> Frame:
    """A Frame from message bytes (or the decoded JSON object) of any readable frame format.

    ``previous``: the frame decoded just before this one in the same chunk (a format-3 predicted
    frame is coded against it; ignored for every other frame).
    Raises ValueError naming what is wrong for malformed data or an unknown format;
    :class:`MissingReference` (a ValueError) for a predicted frame without its reference frame.
    """
    d = decode_json(data) if isinstance(data, (bytes, bytearray, memoryview)) else data
    if not isinstance(d, Mapping):
        raise ValueError(f"a frame must be a JSON object, got {type(d).__name__}")
    fmt = d.get("format")
    if fmt == FRAME_FORMAT:
        return Frame.from_dict(d)
    if fmt not in (COMPACT_FORMAT, CODEC_FORMAT):
        raise ValueError(f"unsupported frame format {fmt!r} (this swarmdeck reads formats {list(READABLE_FORMATS)})")
    try:
        exact = _predicted_fields(d, previous) if fmt == CODEC_FORMAT and d.get("pred") is not None else {}
        return _decode_v2(d, exact)
    except KeyError as exc:
        raise ValueError(f"frame is missing field {exc.args[0]!r}") from None


def _predicted_fields(d: Mapping[str, Any], previous: Frame | None) -> dict[str, np.ndarray]:
    """ids, poses, v, w of the predicted frame ``d``, reconstructed from ``previous`` and checked."""
    pred = d["pred"]
    ref, crc = (pred.get("ref"), pred.get("crc")) if isinstance(pred, Mapping) else (None, None)
    if type(ref) is not int or type(crc) is not int:
        raise ValueError("frame field 'pred' must be an object {ref: tick, crc: integer}")
    if previous is None or previous.tick != ref:
        have = "none" if previous is None else f"tick {previous.tick}"
        raise MissingReference(f"frame of tick {d.get('tick')!r} is predicted from tick {ref}, "
                               f"which was not read before it (previous frame: {have})")
    out = {}
    for name, dtype in EXACT_FIELDS:
        r = unpack_array(d[name], name)
        want = np.shape(getattr(previous, name))
        if r.dtype != np.dtype("<u8") or r.shape != want:
            raise ValueError(f"frame field {name!r}: residuals of type {r.dtype.str} shape {r.shape}, "
                             f"expected <u8 of the reference frame's shape {want}")
        bits = _unzigzag(r) + _predicted_bits(previous, name)
        out[name] = bits.view(np.dtype(dtype)).astype(np.int64 if name == "ids" else np.float64)
    if exact_crc(out["ids"], out["poses"], out["v"], out["w"]) != crc:
        raise ValueError(f"frame of tick {d.get('tick')!r}: the poses and commands reconstructed from tick {ref} "
                         "fail their checksum (a damaged message, or a prediction this machine computes differently)")
    return out


def _decode_v2(d: Mapping[str, Any], exact: Mapping[str, np.ndarray]) -> Frame:
    poses = exact["poses"] if exact else unpack_array(d["poses"], "poses").astype(float)
    if poses.ndim != 2 or poses.shape[1] != 3:
        raise ValueError(f"frame field 'poses' must have shape (n,3), got {poses.shape}")
    v = exact["v"] if exact else unpack_array(d["v"], "v").astype(float)
    w = exact["w"] if exact else unpack_array(d["w"], "w").astype(float)
    n = poses.shape[0]
    if v.shape != (n,) or w.shape != (n,):
        raise ValueError(f"frame fields 'v', 'w' must have shape ({n},), got {v.shape} and {w.shape}")
    lookahead = _dec_float(d["lookahead"])
    safe = derived_safe(poses, v, w, lookahead)
    delta = unpack_array(d["nominal_minus_safe"], "nominal_minus_safe").astype(float)
    if delta.shape != (n, 2):
        raise ValueError(f"frame field 'nominal_minus_safe' must have shape ({n}, 2), got {delta.shape}")
    nominal = safe + delta
    base = dict(d)
    for k in (*_BIG, "pred"):
        base.pop(k, None)
    base.update({"format": FRAME_FORMAT, "ids": [], "poses": [], "seen": [], "nominal": [], "safe": [],
                 "v": [], "w": [], "barrier": None, "coverage": None})
    shell = Frame.from_dict(base)  # every scalar field, checked as in format 1
    barrier = None
    if d.get("barrier") is not None:
        bd = dict(d["barrier"])
        pairs = unpack_array(bd.pop("active_pairs"), "barrier.active_pairs").astype(np.int64)
        pairs = pairs.reshape(-1, 2)
        if pairs.size and (pairs.min() < 0 or pairs.max() >= n):
            raise ValueError(f"frame field 'barrier.active_pairs' names robots outside 0..{n - 1}")
        h = active_h(poses, pairs, lookahead, _dec_float(bd["safety_distance"]))
        inter = unpack_array(bd.pop("intervention"), "barrier.intervention").astype(float)
        barrier = BarrierFrame.from_dict({**bd, "active_pairs": pairs.tolist(), "active_h": h.tolist(),
                                          "intervention": inter.tolist()})
    coverage = None
    if d.get("coverage") is not None:
        coverage = _decode_coverage(d["coverage"], poses, shell, lookahead)
    fleet = {}
    for name, dtype in _FLEET:
        if d.get(name) is not None:
            arr = unpack_array(d[name], name).astype(dtype)
            if arr.shape != (n,):
                raise ValueError(f"frame field {name!r} must have shape ({n},), got {arr.shape}")
            fleet[name] = arr
    sensors = None if d.get("sensors") is None else SensorsFrame.unpacked(d["sensors"], unpack_array, n)
    return Frame(
        tick=shell.tick, time=shell.time, run_time=shell.run_time, dt=shell.dt, bounds=shell.bounds,
        lookahead=lookahead, poses=poses, ids=exact["ids"] if exact else unpack_array(d["ids"], "ids").astype(np.int64),
        seen=unpack_array(d["seen"], "seen").astype(bool), nominal=nominal, safe=safe, v=v, w=w,
        barrier=barrier, coverage=coverage, density=shell.density, contacts=shell.contacts,
        behaviour=shell.behaviour, run_state=shell.run_state, params=shell.params, events=shell.events,
        alerts=shell.alerts, health=shell.health, timing=shell.timing, image_ref=shell.image_ref, **fleet,
        sensors=sensors,
    )


def _decode_coverage(cd: Mapping[str, Any], poses: np.ndarray, shell: Frame, lookahead: float) -> CoverageFrame:
    cost_h, mean_distance = _dec_float(cd["cost_H"]), _dec_float(cd["mean_centroid_distance"])
    warning = cd.get("packing_warning")
    config = geometry_config(cd.get("config"), shell.bounds)
    if cd.get("geometry") == "derived" and len(poses) and shell.density is not None:
        derived = derived_coverage(poses, lookahead, shell.density, config)
        if derived is not None:
            return CoverageFrame.from_geometry(derived, cost_H=cost_h, mean_centroid_distance=mean_distance,
                                               packing_warning=warning)
    if "centroids" in cd:
        return CoverageFrame(centroids=unpack_array(cd["centroids"], "coverage.centroids").astype(float),
                             masses=unpack_array(cd["masses"], "coverage.masses").astype(float),
                             edges=np.zeros((0, 2, 2)), neighbours=np.zeros((0, 2), dtype=np.int64),
                             cost_H=cost_h, mean_centroid_distance=mean_distance, packing_warning=warning)
    n = len(poses)
    return CoverageFrame(centroids=np.zeros((n, 2)), masses=np.zeros(n), edges=np.zeros((0, 2, 2)),
                         neighbours=np.zeros((0, 2), dtype=np.int64), cost_H=cost_h,
                         mean_centroid_distance=mean_distance, packing_warning=warning)


def geometry_config(changes: Any, bounds: Bounds) -> GeometryConfig:
    """The coverage geometry config a frame's ``coverage.config`` describes on the frame's ``bounds``
    (absent, as in every recording made before it was stored: the defaults). ValueError naming the field."""
    if changes is not None and not isinstance(changes, Mapping):
        raise ValueError(f"frame field 'coverage.config' must be an object, got {type(changes).__name__}")
    try:
        return GeometryConfig.from_changes(changes, bounds)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"frame field 'coverage.config': {exc}") from None


def derived_coverage(poses: np.ndarray, lookahead: float, density: Any, config: GeometryConfig) -> CoverageGeometry | None:
    """What the coverage behaviour computed from the poses, computed again by the same function
    (:func:`swarmdeck.coverage.coverage_geometry` on the look-ahead points, with the frame's coverage
    config); None when the diagram cannot be built (nothing to draw, never a failed read)."""
    try:
        geo = coverage_geometry(lookahead_points(poses, lookahead), density, config)
    except Exception:  # noqa: BLE001 - poses the pre-conditioning refuses: nothing to draw
        return None
    return geo if geo.ok else None


# ---------------------------------------------------------------------------- the other channels
@dataclass(frozen=True)
class RecordedDatagram:
    """One recorded input datagram: raw ``data``, ``peer`` (tuple (host, port) or name),
    ``transport``, console receive time ``t`` (s), receiving ``listener`` name or None."""

    t: float
    data: bytes
    peer: object
    transport: str
    listener: str | None


@dataclass(frozen=True)
class RecordedEvent:
    """``t``: recording time, s since the first frame (session time: what ``swarmdeck play`` seeks
    to); ``kind`` ("operator", "frame", "recorder", …); ``text``; ``console_t``: the loop's clock, s."""

    t: float
    kind: str
    text: str
    console_t: float = float("nan")


def datagram_message(data: bytes, peer: object, transport: str, t: float, listener: str | None) -> dict[str, Any]:
    """The ``/swarmdeck/datagram`` message of a raw input datagram received at console time ``t`` s
    (the bytes base64, a (host, port) peer as a list, any other peer as its string)."""
    peer_j = list(peer) if isinstance(peer, (tuple, list)) else str(peer)
    return {"t": t, "data": base64.b64encode(data).decode("ascii"), "peer": peer_j, "transport": transport,
            "listener": listener}


def decode_datagram(data: bytes) -> RecordedDatagram:
    """Inverse of :func:`datagram_message` (from the message bytes); ValueError, KeyError or TypeError
    for a malformed message."""
    d = json.loads(data)
    peer = d["peer"]
    return RecordedDatagram(float(d["t"]), base64.b64decode(d["data"], validate=True),
                            tuple(peer) if isinstance(peer, list) else peer, str(d["transport"]), d.get("listener"))


def event_message(t: float, kind: str, text: str) -> dict[str, Any]:
    """The ``/swarmdeck/event`` message of an event at console time ``t`` s."""
    return {"t": t, "kind": kind, "text": text}


def decode_event(data: bytes, rel: float) -> RecordedEvent:
    """Inverse of :func:`event_message` (from the message bytes), at recording time ``rel`` s;
    ValueError, KeyError or TypeError for a malformed message."""
    d = json.loads(data)
    return RecordedEvent(rel, str(d["kind"]), str(d["text"]), float(d["t"]))


def decode_config(data: bytes) -> dict[str, Any]:
    """The ``/swarmdeck/config`` message (the recorder's ``_write_config``) as a dict; ValueError
    for bad JSON, TypeError or ValueError for a message that is not an object."""
    return dict(json.loads(data))


def metadata_record(meta: Mapping[str, Any]) -> dict[str, str]:
    """The ``swarmdeck`` metadata record's string map: every value JSON-encoded."""
    return {k: json.dumps(v) for k, v in meta.items()}


def decode_metadata(record: Mapping[str, str]) -> dict[str, Any]:
    """Inverse of :func:`metadata_record`; a value that is not JSON stays the string it is."""
    out: dict[str, Any] = {}
    for k, v in record.items():
        try:
            out[k] = json.loads(v)
        except ValueError:
            out[k] = v
    return out


__all__ = ["RecordedDatagram", "RecordedEvent", "datagram_message", "decode_datagram", "event_message",
           "decode_event", "decode_config", "metadata_record", "decode_metadata", "CODEC_FORMAT", "COMPACT_FORMAT", "READABLE_FORMATS", "EXACT_FIELDS", "MissingReference", "can_predict",
           "exact_crc", "encode_frame", "decode_frame", "frame_message", "pack_array",
           "unpack_array", "derived_coverage", "geometry_config", "derived_safe", "encode_json", "decode_json"]
