"""What a sandboxed script's robots sense, computed on the trusted side and sent to the child (issue 28).

The child never computes a reading: when the script gives its Arena sensors (``Arena(sensing=...)``,
``arena.use_sensors``, rps 2.x's ``use_distance_sensors=True``), the child sends the configuration once
(``{"t": "sensors", "config": {...}}``, :func:`sensing_message`); the trusted side builds the sensors on its own
Arena — its seed, its obstacles (the lab's and the script's), the commands the robots really ran (after the wheel
limits and the barrier), or the robots' own firmware readings — and sends every tick's readings before that tick's
poses (``{"t": "readings", ...}``, :func:`readings_message`). LEDs the script sets go the other way
(``{"t": "leds", "rgb": bytes}``, :func:`leds_from_message`, checked like every message the child sends).

Arrays travel as ``[dtype, shape, bytes]`` (little-endian). Parent → child messages are decoded by the child
(:func:`readings_from_message`); child → parent ones by the trusted side, which refuses anything malformed with
a :class:`~swarmdeck.console.sandbox.protocol.ProtocolError` naming it.
"""
from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
from numpy.typing import NDArray

from swarmdeck.console.sandbox.protocol import ProtocolError
from swarmdeck.sensing import SensingConfig, SensorReadings
from swarmdeck.sensing.config import DistanceSensorConfig, ImuConfig, RangeBearingConfig
from swarmdeck.sensing.models import RangeBearing

__all__ = ["leds_from_message", "leds_message", "readings_from_message", "readings_message",
           "sensing_from_message", "sensing_message"]

_PARTS = (("distance", DistanceSensorConfig), ("range_bearing", RangeBearingConfig), ("imu", ImuConfig))
_ARRAYS = ("distances", "origins", "endpoints", "encoders", "accel", "gyro", "mag", "orientation", "leds")
_MAX_SENSORS = 64  # distance sensors per robot a script may ask for


def sensing_message(config: SensingConfig) -> dict[str, Any]:
    """The child's ``sensors`` message: which sensors the script's robots have (plain values only)."""
    return {"t": "sensors", "config": dataclasses.asdict(config)}


def _tuples(value: Any) -> Any:
    return tuple(_tuples(v) for v in value) if isinstance(value, list) else value


def sensing_from_message(message: dict[str, Any]) -> SensingConfig:
    """The :class:`~swarmdeck.sensing.SensingConfig` of a ``sensors`` message (checked by its own ``__post_init__``);
    ProtocolError naming the part that is not a valid configuration."""
    raw = message.get("config")
    if not isinstance(raw, dict) or set(raw) - {"distance", "range_bearing", "imu", "leds"}:
        raise ProtocolError(f"'sensors' message: config must be a map of distance, range_bearing, imu, leds; "
                            f"got {str(raw)[:80]!r}")
    parts: dict[str, Any] = {}
    for name, kind in _PARTS:
        value = raw.get(name)
        if value is None:
            parts[name] = None
            continue
        if not isinstance(value, dict):
            raise ProtocolError(f"'sensors' message: {name} must be a map, got {str(value)[:80]!r}")
        if name == "distance" and len(value.get("poses") or ()) > _MAX_SENSORS:
            raise ProtocolError(f"'sensors' message: at most {_MAX_SENSORS} distance sensors per robot")
        try:
            parts[name] = kind(**{k: _tuples(v) for k, v in value.items()})
        except (TypeError, ValueError) as exc:
            raise ProtocolError(f"'sensors' message: {name}: {exc}") from None
    try:
        return SensingConfig(leds=raw.get("leds", True), **parts)
    except (TypeError, ValueError) as exc:
        raise ProtocolError(f"'sensors' message: {exc}") from None


def _pack(array: NDArray[Any]) -> list[Any]:
    a = np.asarray(array)
    little = a.astype(a.dtype.newbyteorder("<"), copy=False)
    return [little.dtype.str, list(a.shape), np.ascontiguousarray(little).tobytes()]


def _unpack(raw: Any) -> NDArray[Any]:
    dtype, shape, data = raw
    out = np.frombuffer(data, dtype=np.dtype(dtype)).reshape(shape).astype(np.dtype(dtype).newbyteorder("="))
    out.flags.writeable = False
    return out


def readings_message(k: int, readings: SensorReadings) -> dict[str, Any]:
    """The trusted side's ``readings`` message for tick ``k``: every present array of ``readings``."""
    message: dict[str, Any] = {"t": "readings", "k": int(k)}
    for name in _ARRAYS:
        value = getattr(readings, name)
        if value is not None:
            message[name] = _pack(value)
    rb = readings.range_bearing
    if rb is not None:
        message["range_bearing"] = [_pack(rb.i), _pack(rb.j), _pack(rb.range), _pack(rb.bearing)]
    return message


def readings_from_message(message: dict[str, Any]) -> SensorReadings:
    """The child's :class:`~swarmdeck.sensing.SensorReadings` of a ``readings`` message (read-only arrays)."""
    fields: dict[str, Any] = {name: _unpack(message[name]) for name in _ARRAYS if message.get(name) is not None}
    rb = message.get("range_bearing")
    if rb is not None:
        i, j, r, b = (_unpack(part) for part in rb)
        fields["range_bearing"] = RangeBearing(i.astype(np.intp), j.astype(np.intp), r, b)
    return SensorReadings(**fields)


def leds_message(rgb: NDArray[np.uint8]) -> dict[str, Any]:
    """The child's ``leds`` message: every robot's LED ``(N, 3)`` 0…255, as the script set them."""
    return {"t": "leds", "rgb": np.ascontiguousarray(rgb, dtype=np.uint8).tobytes()}


def leds_from_message(message: dict[str, Any], n: int) -> NDArray[np.uint8]:
    """The ``(n, 3)`` uint8 LEDs of a ``leds`` message; ProtocolError on a wrong size."""
    raw = message.get("rgb")
    if not isinstance(raw, (bytes, bytearray)) or len(raw) != 3 * n:
        got = f"{len(raw)} bytes" if isinstance(raw, (bytes, bytearray)) else type(raw).__name__
        raise ProtocolError(f"'leds' message: rgb must be {3 * n} bytes (N x 3 values 0..255), got {got}")
    return np.frombuffer(raw, dtype=np.uint8).reshape(n, 3).copy()
