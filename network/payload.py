"""What a message may carry, its size in bytes and the copy a receiver gets.

A payload is a *message value*: ``None``, ``bool``, ``int`` (64-bit), finite or non-finite ``float``,
``str``, ``bytes``, lists and tuples of message values (a tuple arrives as a list), dicts with ``str`` keys and
message-value values, and numpy arrays of a bool, integer or float dtype (at most :data:`MAX_ARRAY_DIMS`
dimensions; numpy scalars count as their Python value). Nesting is at most :data:`MAX_DEPTH` deep.
It is encoded with msgpack (numpy arrays as an extension holding dtype, shape and the little-endian
bytes); the message's size is the length of that encoding, and the receiver gets a fresh decode of it, so
nothing the receiver does can reach the sender's object.
"""
from __future__ import annotations

import struct
from typing import Any

import msgspec
import numpy as np

from swarmdeck.network.errors import PayloadError

__all__ = ["MAX_ARRAY_DIMS", "MAX_DEPTH", "decode_payload", "encode_payload"]

#: Deepest nesting of lists/dicts in a payload.
MAX_DEPTH = 32
#: Most dimensions of an array in a payload.
MAX_ARRAY_DIMS = 8
_ARRAY_EXT = 1
_KINDS = "biuf"  # bool, signed, unsigned, float


def _check(value: Any, depth: int, where: str, max_bytes: int) -> None:
    """Raise PayloadError naming the first value (by its path) that is not a message value, or for a container
    with more items than ``max_bytes`` (each item encodes to at least one byte: too big, found without walking it)."""
    if depth > MAX_DEPTH:
        raise PayloadError(f"payload nests deeper than {MAX_DEPTH} levels at {where}")
    if value is None or isinstance(value, (bool, int, float, str, bytes, np.bool_, np.integer, np.floating)):
        if isinstance(value, int) and not isinstance(value, bool) and not -(2**63) <= value < 2**64:
            raise PayloadError(f"payload integer at {where} does not fit in 64 bits")
        return
    if isinstance(value, np.ndarray):
        if value.dtype.kind not in _KINDS or value.ndim > MAX_ARRAY_DIMS:
            raise PayloadError(f"payload array at {where} has dtype {value.dtype} and {value.ndim} dimensions; "
                               f"only bool, integer and float arrays of at most {MAX_ARRAY_DIMS} dimensions travel")
        return
    if isinstance(value, (list, tuple, dict)) and len(value) > max_bytes:
        raise PayloadError(f"payload container at {where} has {len(value)} items: it exceeds the largest message, "
                           f"{max_bytes} bytes")
    if isinstance(value, (list, tuple)):
        for k, item in enumerate(value):
            _check(item, depth + 1, f"{where}[{k}]", max_bytes)
        return
    if isinstance(value, dict):
        for key, item in value.items():
            if not isinstance(key, str):
                raise PayloadError(f"payload dict at {where} has a key of type {type(key).__name__}; keys must be str")
            _check(item, depth + 1, f"{where}[{key!r}]", max_bytes)
        return
    raise PayloadError(f"payload value at {where} is a {type(value).__module__}.{type(value).__qualname__}, which is "
                       "not serialisable: send None, bool, int, float, str, bytes, lists, str-keyed dicts or numpy arrays")


def _enc_hook(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        dtype = value.dtype.newbyteorder("<") if value.dtype.itemsize > 1 else value.dtype
        code = dtype.str.encode()
        head = struct.pack(f"<B{len(code)}sB{value.ndim}q", len(code), code, value.ndim, *value.shape)
        return msgspec.msgpack.Ext(_ARRAY_EXT, head + value.astype(dtype, copy=False).tobytes(order="C"))
    if isinstance(value, np.generic):
        return value.item()
    raise NotImplementedError(type(value).__name__)


def _ext_hook(code: int, data: memoryview) -> Any:
    """An array from its extension: dtype string length (u8), dtype string, ndim (u8), shape (int64 × ndim), bytes."""
    if code != _ARRAY_EXT:
        raise PayloadError(f"unknown payload extension {code}")
    length = data[0]
    dtype = np.dtype(bytes(data[1:1 + length]).decode())
    ndim = data[1 + length]
    offset = 2 + length + 8 * ndim
    shape = struct.unpack_from(f"<{ndim}q", data, 2 + length)
    return np.frombuffer(data, dtype=dtype, offset=offset).reshape(shape).copy()


_encoder = msgspec.msgpack.Encoder(enc_hook=_enc_hook)
_decoder = msgspec.msgpack.Decoder(ext_hook=_ext_hook)


def _quick_size(value: Any) -> int:
    """A lower bound of the encoded size of a flat value, bytes (so a 10 MB payload is refused before encoding)."""
    if isinstance(value, (str, bytes)):
        return len(value)
    if isinstance(value, np.ndarray):
        return int(value.nbytes)
    return 0


def encode_payload(payload: Any, max_bytes: int) -> bytes:
    """The encoding of ``payload``; :class:`PayloadError` if it is not a message value or exceeds ``max_bytes``."""
    size = _quick_size(payload)
    if size > max_bytes:
        raise PayloadError(f"payload of at least {size} bytes exceeds the largest message, {max_bytes} bytes")
    _check(payload, 0, "payload", max_bytes)
    try:
        data = _encoder.encode(payload)
    except (TypeError, ValueError, OverflowError, NotImplementedError) as exc:
        raise PayloadError(f"payload is not serialisable: {exc}") from exc
    if len(data) > max_bytes:
        raise PayloadError(f"payload of {len(data)} bytes exceeds the largest message, {max_bytes} bytes")
    return data


def decode_payload(data: bytes) -> Any:
    """A fresh copy of the payload encoded in ``data``."""
    return _decoder.decode(data)
