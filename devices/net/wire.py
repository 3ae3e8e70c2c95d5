"""JSON payloads of the GRITSBot X wire format (REFERENCE.md §9), encoded and checked.

* command on ``matlab_api/<id>``: ``{"v": m/s, "w": rad/s, "left_led": [r,g,b], "right_led": [r,g,b]}``
  (LED keys only when set) — exactly the Robotarium's keys, nothing else;
* status on ``<id>/status``: ``{"batt_volt": V, "charge_status": bool}`` plus optional
  extras the simulated fleet adds (``cmd_age`` s, ``seq`` counter, ``node`` name,
  ``stamp`` s on the robot's clock) — readers that know only the Robotarium keys
  ignore them;
* poses on ``overhead_tracker/all_robot_pose_data``:
  ``{"<id>": {"x", "y", "theta", "batt_volt", "charge_status"}, …}`` (optionally
  ``"stamp"`` per robot, which lets receivers drop out-of-order rows).

Decoders never raise anything but :class:`WireError`, whose message names what
was wrong and what was expected.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmdeck.core.errors import SwarmdeckError


class WireError(ValueError, SwarmdeckError):
    """A payload that does not follow the wire format."""


def _num(obj: dict, key: str, what: str) -> float:
    if key not in obj:
        raise WireError(f"{what}: missing key {key!r}")
    x = obj[key]
    if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
        raise WireError(f"{what}: {key!r} must be a finite number, got {x!r}")
    return float(x)


def _load_object(payload: bytes, what: str) -> dict:
    try:
        obj = json.loads(payload)
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise WireError(f"{what}: not valid JSON ({exc.msg if hasattr(exc, 'msg') else exc}): {payload[:80]!r}") from None
    except RecursionError:
        raise WireError(f"{what}: JSON nested too deeply") from None
    if not isinstance(obj, dict):
        raise WireError(f"{what}: expected a JSON object, got {type(obj).__name__}")
    return obj


def _led(x: object, key: str, what: str) -> tuple[int, int, int]:
    if (
        not isinstance(x, list)
        or len(x) != 3
        or not all(isinstance(c, int) and not isinstance(c, bool) and 0 <= c <= 255 for c in x)
    ):
        raise WireError(f"{what}: {key!r} must be [r, g, b] with integers 0..255, got {x!r}")
    return (x[0], x[1], x[2])


# ------------------------------------------------------------------ commands
def encode_commands(v: ArrayLike, w: ArrayLike, leds: NDArray[np.uint8] | None = None) -> list[bytes]:
    """One command payload per robot: ``v, w (K,)``, ``leds (K, 2, 3)`` or None.

    Floats are written with Python's shortest round-trip repr, so the robot
    decodes exactly the value sent.
    """
    vs = np.asarray(v, dtype=float).tolist()
    ws = np.asarray(w, dtype=float).tolist()
    if leds is None:
        return [f'{{"v": {a!r}, "w": {b!r}}}'.encode() for a, b in zip(vs, ws)]
    ls = np.asarray(leds).tolist()
    return [
        f'{{"v": {a!r}, "w": {b!r}, "left_led": {json.dumps(l[0])}, "right_led": {json.dumps(l[1])}}}'.encode()
        for a, b, l in zip(vs, ws, ls)
    ]


@dataclass(frozen=True)
class Command:
    """A decoded command: v m/s, w rad/s, optional LED colours."""

    v: float
    w: float
    left_led: tuple[int, int, int] | None = None
    right_led: tuple[int, int, int] | None = None


def decode_command(payload: bytes) -> Command:
    """Parse a ``matlab_api/<id>`` payload; :class:`WireError` when malformed."""
    what = "command"
    obj = _load_object(payload, what)
    v = _num(obj, "v", what)
    w = _num(obj, "w", what)
    left = _led(obj["left_led"], "left_led", what) if "left_led" in obj else None
    right = _led(obj["right_led"], "right_led", what) if "right_led" in obj else None
    return Command(v, w, left, right)


# ------------------------------------------------------------------ status
@dataclass(frozen=True)
class Status:
    """A decoded robot status report."""

    batt_volt: float
    charge_status: bool
    cmd_age: float | None = None
    seq: int | None = None
    node: str | None = None
    stamp: float | None = None


def encode_status(batt_volt: float, charge_status: bool, *, cmd_age: float | None = None, seq: int | None = None,
                  node: str | None = None, stamp: float | None = None) -> bytes:
    """``{"batt_volt", "charge_status"}`` plus the optional extras that are given."""
    obj: dict[str, object] = {"batt_volt": round(float(batt_volt), 3), "charge_status": bool(charge_status)}
    if cmd_age is not None:
        obj["cmd_age"] = round(float(cmd_age), 4) if math.isfinite(cmd_age) else None
    if seq is not None:
        obj["seq"] = int(seq)
    if node is not None:
        obj["node"] = str(node)
    if stamp is not None:
        obj["stamp"] = round(float(stamp), 4)
    return json.dumps(obj).encode()


_CHARGE_WORDS = {"true": True, "false": False, "charging": True, "discharging": False, "1": True, "0": False}


def _charge(x: object, what: str) -> bool:
    if isinstance(x, bool):
        return x
    if isinstance(x, int) and x in (0, 1):
        return bool(x)
    if isinstance(x, str) and x.lower() in _CHARGE_WORDS:
        return _CHARGE_WORDS[x.lower()]
    raise WireError(f"{what}: 'charge_status' must be true/false (or 0/1), got {x!r}")


def decode_status(payload: bytes) -> Status:
    """Parse a ``<id>/status`` payload; :class:`WireError` when malformed."""
    what = "status"
    obj = _load_object(payload, what)
    batt = _num(obj, "batt_volt", what)
    if "charge_status" not in obj:
        raise WireError(f"{what}: missing key 'charge_status'")
    charging = _charge(obj["charge_status"], what)
    cmd_age = obj.get("cmd_age")
    if cmd_age is not None:
        cmd_age = _num(obj, "cmd_age", what)
    seq = obj.get("seq")
    if seq is not None and (isinstance(seq, bool) or not isinstance(seq, int)):
        raise WireError(f"{what}: 'seq' must be an integer, got {seq!r}")
    node = obj.get("node")
    if node is not None and not isinstance(node, str):
        raise WireError(f"{what}: 'node' must be a string, got {node!r}")
    stamp = _num(obj, "stamp", what) if obj.get("stamp") is not None else None
    return Status(batt, charging, cmd_age, seq, node, stamp)


# ------------------------------------------------------------------ poses
def encode_poses(ids: ArrayLike, poses: ArrayLike, batt_volt: ArrayLike, charging: ArrayLike, *,
                 decimals: int = 3, stamp: float | None = None) -> bytes:
    """Tracker output for robots ``ids (K,)`` with poses ``(K, 3)``.

    Values are rounded to ``decimals`` (the camera tracker uses 2, the Vicon one 3).
    ``stamp`` (sender's clock, s) is added to every row when given.
    """
    ids_l = np.asarray(ids, dtype=np.int64).tolist()
    p = np.round(np.asarray(poses, dtype=float), decimals).tolist()
    b = np.round(np.asarray(batt_volt, dtype=float), 3).tolist()
    c = np.asarray(charging, dtype=bool).tolist()
    extra = f', "stamp": {round(float(stamp), 4)!r}' if stamp is not None else ""
    rows = (
        f'"{i}": {{"x": {q[0]!r}, "y": {q[1]!r}, "theta": {q[2]!r}, "batt_volt": {bv!r}, '
        f'"charge_status": {"true" if ch else "false"}{extra}}}'
        for i, q, bv, ch in zip(ids_l, p, b, c)
    )
    return ("{" + ", ".join(rows) + "}").encode()


@dataclass(frozen=True)
class PoseMessage:
    """A decoded tracker message: the well-formed rows and what was wrong with the others."""

    ids: NDArray[np.intp]
    poses: NDArray[np.float64]
    batt_volt: NDArray[np.float64]  # NaN when absent
    charging: NDArray[np.bool_]
    stamps: NDArray[np.float64]  # NaN when absent
    problems: tuple[str, ...]


def decode_poses(payload: bytes) -> PoseMessage:
    """Parse ``overhead_tracker/all_robot_pose_data``.

    A payload that is not a JSON object raises :class:`WireError`; a bad row
    (non-integer key, missing or non-finite x/y/theta, repeated id) is skipped and
    described in ``problems``.
    """
    what = "poses"
    obj = _load_object(payload, what)
    ids: list[int] = []
    rows: list[tuple[float, float, float]] = []
    batt: list[float] = []
    charge: list[bool] = []
    stamps: list[float] = []
    problems: list[str] = []
    for key, row in obj.items():  # one pass over the message (tens to hundreds of rows)
        rid = int(key) if key.isascii() and key.isdigit() and len(key) <= 9 else None
        if rid is None:
            problems.append(f"{what}: key {key!r} is not a robot id (expected a non-negative integer)")
            continue
        if not isinstance(row, dict):
            problems.append(f"{what}: robot {key}: expected an object with x, y, theta, got {type(row).__name__}")
            continue
        try:
            q = (_num(row, "x", f"{what}: robot {key}"), _num(row, "y", f"{what}: robot {key}"),
                 _num(row, "theta", f"{what}: robot {key}"))
        except WireError as exc:
            problems.append(str(exc))
            continue
        b = row.get("batt_volt")
        st = row.get("stamp")
        ids.append(rid)
        rows.append(q)
        batt.append(float(b) if isinstance(b, (int, float)) and not isinstance(b, bool) else math.nan)
        charge.append(bool(row.get("charge_status")) if isinstance(row.get("charge_status"), (bool, int)) else False)
        stamps.append(float(st) if isinstance(st, (int, float)) and not isinstance(st, bool) else math.nan)
    id_arr = np.asarray(ids, dtype=np.intp)
    # JSON objects with a repeated key keep the last value in Python; ids can still
    # repeat as "7" and "07": keep the first of each.
    uniq, first = np.unique(id_arr, return_index=True)
    if len(uniq) != len(id_arr):
        rest = np.setdiff1d(np.arange(len(id_arr)), first)
        problems.append(f"{what}: robot id(s) {np.unique(id_arr[rest]).tolist()} repeated in one message; first kept")
    order = first
    pose_arr = np.asarray(rows, dtype=float).reshape(-1, 3)
    return PoseMessage(
        uniq,
        pose_arr[order],
        np.asarray(batt, dtype=float)[order],
        np.asarray(charge, dtype=bool)[order],
        np.asarray(stamps, dtype=float)[order],
        tuple(problems),
    )
