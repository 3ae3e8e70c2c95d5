"""Configuration from files and tables: mapping → frozen dataclass, written once.

Every configuration class of swarmdeck is a frozen dataclass whose ``__post_init__`` checks its
values (with :mod:`swarmdeck.core.checks`). This module turns outside input into such objects:

* :func:`read_toml` reads a TOML file (the one place that does);
* :func:`check_keys` refuses a non-table and unknown keys, naming them and the known ones;
* :func:`from_mapping` does both for a dataclass, converts the values that need it (lists to
  tuples, nested tables) and turns any bad value into one error that names the table and the
  key — and the file, when ``source`` is given.

Errors are :class:`ConfigError` (a ValueError) unless the caller names its own error type.
"""
from __future__ import annotations

import dataclasses
import tomllib
from collections.abc import Callable, Collection, Mapping
from pathlib import Path
from typing import Any, TypeVar

from .errors import SwarmdeckError

T = TypeVar("T")

#: The usual unknown-key message; ``{what}`` names the table, ``{unknown}``/``{known}`` are sorted lists.
UNKNOWN_KEYS = "unknown {what} keys {unknown}; expected some of {known}"


class ConfigError(ValueError, SwarmdeckError):
    """A configuration value, table or file that cannot be used; the message names the key (and the file)."""


def read_toml(path: str | Path, error: type[Exception] = ConfigError) -> dict[str, Any]:
    """The document in TOML file ``path``; ``error`` naming the file if it is unreadable or not TOML."""
    try:
        with open(path, "rb") as f:
            return tomllib.load(f)
    except OSError as exc:
        raise error(f"cannot read config file {path}: {exc.strerror}") from None
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{path} is not valid TOML: {exc}") from None


def _prefix(source: str | Path | None) -> str:
    return f"{source}: " if source is not None else ""


def check_keys(data: object, known: Collection[str], what: str, *, error: type[Exception] = ConfigError,
               template: str = UNKNOWN_KEYS, source: str | Path | None = None) -> dict[str, Any]:
    """``data`` as a new dict; ``error`` unless it is a mapping whose keys are all in ``known``.

    ``template`` words the unknown-key message (fields ``what``, ``unknown``, ``known``);
    ``source`` (a file) is put in front of every message.
    """
    if not isinstance(data, Mapping):
        raise error(f"{_prefix(source)}{what} must be a table/dict, got {type(data).__name__}")
    unknown = sorted(set(data) - set(known), key=str)
    if unknown:
        raise error(_prefix(source) + template.format(what=what, unknown=unknown, known=sorted(known)))
    return dict(data)


def field_names(cls: type) -> set[str]:
    """Names of the dataclass fields of ``cls`` (its settable keys)."""
    return {f.name for f in dataclasses.fields(cls) if f.init}


def from_mapping(cls: Callable[..., T], data: object, what: str, *,
                 convert: Mapping[str, Callable[[Any], Any]] | None = None,
                 error: type[Exception] = ConfigError, template: str = UNKNOWN_KEYS,
                 source: str | Path | None = None, wrap: str = "{what}: {message}") -> T:
    """Build dataclass ``cls`` from the table ``data``: unknown keys refused (:func:`check_keys`),
    ``convert[key]`` applied to each given key (e.g. ``tuple`` for TOML arrays, a nested
    ``from_mapping`` for a sub-table), then ``cls(**values)``.

    A TypeError or ValueError from a conversion becomes ``error`` naming the key; one from the
    class's own checks becomes ``error(wrap.format(what=what, message=...))`` unless it already is
    an ``error``; ``source`` goes in front. A nested table's :class:`ConfigError` keeps its message (with ``source`` in front).
    """
    kw = check_keys(data, field_names(cls), what, error=error, template=template, source=source)  # type: ignore[arg-type]
    for key, fn in (convert or {}).items():
        if key in kw:
            try:
                kw[key] = fn(kw[key])
            except ConfigError as exc:  # a nested table's own message: only the file goes in front
                message = str(exc)
                if isinstance(exc, error) and message.startswith(_prefix(source)):
                    raise
                raise error(message if message.startswith(_prefix(source)) else _prefix(source) + message) from None
            except (TypeError, ValueError) as exc:
                raise error(_prefix(source) + wrap.format(what=what, message=f"{key}: {exc}")) from None
    try:
        return cls(**kw)
    except error:
        raise
    except (TypeError, ValueError) as exc:
        raise error(_prefix(source) + wrap.format(what=what, message=exc)) from None


def floats(value: Any) -> tuple[float, ...]:
    """A TOML array of numbers as a tuple of floats (TypeError/ValueError otherwise)."""
    if isinstance(value, (str, bytes, Mapping)):
        raise ValueError(f"expected a list of numbers, got {value!r}")
    return tuple(float(v) for v in value)
