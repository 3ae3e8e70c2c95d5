"""The console's TOML configuration file (``swarmdeck console --config FILE``).

Tables (every key optional; defaults from REFERENCE.md)::

    [console]   host = "127.0.0.1", port = 8080, robots = 12, behaviour = "coverage",
                seed = 1, dt = 0.033, max_speed = 0.2, bounds = [-1.6, 1.6, -1.0, 1.0],
                script_budget = dt / 2 (s a script: behaviour may take per tick)
                (or arena = "10x6" instead of bounds: a W x H m arena centred on the origin)
    [behaviour] kappa, law, gain, formation_edge, formation_gain, goals = [[x, y], ...],
                goal_centre = [x, y]
    [safety]    enabled, safety_distance, gamma, class_k, mode ("auto" | "centralised" | "distributed")
    [density]   moving, radius, period, sigma, weight, floor, bump_sigma, bump_weight
    [inputs]    see swarmdeck.inputs.InputConfig (listeners, density, bounds)

Unknown tables or keys and values out of range are errors naming the table and key.
"""
from __future__ import annotations

import tomllib
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

from swarmdeck.console.runtime.behaviours import BehaviourParams
from swarmdeck.console.runtime.loop import DensityParams, LoopConfig, SafetyParams

TABLES = ("console", "behaviour", "safety", "density", "inputs")
CONSOLE_KEYS = ("host", "port", "robots", "behaviour", "seed", "dt", "max_speed", "bounds", "script_budget",
                "arena")
# [console] key -> LoopConfig field (errors name the key, not the field)
LOOP_KEYS = {"robots": "n_robots", "behaviour": "behaviour", "seed": "seed", "dt": "dt", "max_speed": "max_speed",
             "bounds": "bounds", "script_budget": "script_budget"}


def arena_bounds(spec: str) -> tuple[float, float, float, float]:
    """Bounds (x_min, x_max, y_min, y_max) of a ``"WxH"`` arena in m centred on the origin, e.g.
    ``"10x6"`` → (−5, 5, −3, 3); ``×`` works too. ValueError naming the spec otherwise."""
    parts = str(spec).lower().replace("×", "x").split("x")
    try:
        w, h = (float(v) for v in parts)
    except ValueError:
        raise ValueError(f"arena must be WIDTHxHEIGHT in metres, e.g. 10x6, got {spec!r}") from None
    if not (0 < w < 1e4 and 0 < h < 1e4):
        raise ValueError(f"arena sides must be positive metres, got {spec!r}")
    return (-w / 2, w / 2, -h / 2, h / 2)


class ConfigFileError(ValueError):
    """A configuration file that cannot be used; the message names the file, table and key."""


@dataclass(frozen=True)
class ConsoleSettings:
    """What the file says: the loop's config, server address, and the raw ``[inputs]`` table (or None)."""

    loop: LoopConfig
    host: str = "127.0.0.1"
    port: int = 8080
    inputs: dict | None = None


def _table(doc: dict, name: str, path: Path) -> dict:
    t = doc.get(name, {})
    if not isinstance(t, dict):
        raise ConfigFileError(f"{path}: [{name}] must be a table")
    return t


def _build(cls: type, table: dict, name: str, path: Path, convert: dict[str, Any] | None = None) -> Any:
    known = {f.name for f in fields(cls)}
    extra = set(table) - known
    if extra:
        raise ConfigFileError(f"{path}: unknown key(s) {sorted(extra)} in [{name}]; expected some of {sorted(known)}")
    kw = dict(table)
    try:
        for key, fn in (convert or {}).items():
            if key in kw:
                kw[key] = fn(kw[key])
        return cls(**kw)
    except (TypeError, ValueError) as exc:
        raise ConfigFileError(f"{path}: [{name}]: {exc}") from None


def load_settings(path: str | Path) -> ConsoleSettings:
    """Read and validate a console configuration file."""
    p = Path(path)
    try:
        with open(p, "rb") as f:
            doc = tomllib.load(f)
    except OSError as exc:
        raise ConfigFileError(f"cannot read config file {p}: {exc.strerror}") from None
    except tomllib.TOMLDecodeError as exc:
        raise ConfigFileError(f"{p} is not valid TOML: {exc}") from None
    extra = set(doc) - set(TABLES)
    if extra:
        raise ConfigFileError(f"{p}: unknown table(s) {sorted(extra)}; expected some of {list(TABLES)}")
    con = _table(doc, "console", p)
    bad = set(con) - set(CONSOLE_KEYS)
    if bad:
        raise ConfigFileError(f"{p}: unknown key(s) {sorted(bad)} in [console]; expected some of {list(CONSOLE_KEYS)}")
    goals = lambda g: tuple(tuple(float(c) for c in row) for row in g)  # noqa: E731
    bp = _build(BehaviourParams, _table(doc, "behaviour", p), "behaviour", p,
                {"goals": goals, "goal_centre": lambda c: tuple(float(v) for v in c)})
    sp = _build(SafetyParams, _table(doc, "safety", p), "safety", p, {"gamma": float, "safety_distance": float})
    dp = _build(DensityParams, _table(doc, "density", p), "density", p)
    loop_kw: dict[str, Any] = {"behaviour_params": bp, "safety": sp, "density": dp}
    for key, target in LOOP_KEYS.items():  # one key at a time, so the error names the key written
        if key not in con:
            continue
        try:
            value = tuple(float(b) for b in con[key]) if key == "bounds" else con[key]
            LoopConfig(**{target: value})
        except (TypeError, ValueError) as exc:
            message = str(exc).replace(target, key) if target != key else str(exc)
            raise ConfigFileError(f"{p}: [console] {key} = {con[key]!r}: {message}") from None
        loop_kw[target] = value
    try:
        if "arena" in con:
            if "bounds" in con:
                raise ValueError("give arena or bounds, not both")
            loop_kw["bounds"] = arena_bounds(con["arena"])
        loop = LoopConfig(**loop_kw)
    except (TypeError, ValueError) as exc:
        raise ConfigFileError(f"{p}: [console]: {exc}") from None
    host = con.get("host", "127.0.0.1")
    port = con.get("port", 8080)
    if not isinstance(host, str) or not host:
        raise ConfigFileError(f"{p}: [console] host must be a non-empty string, got {host!r}")
    if isinstance(port, bool) or not isinstance(port, int) or not 0 <= port <= 65535:
        raise ConfigFileError(f"{p}: [console] port must be an integer in [0, 65535], got {port!r}")
    inputs = doc.get("inputs")
    if inputs is not None and not isinstance(inputs, dict):
        raise ConfigFileError(f"{p}: [inputs] must be a table")
    return ConsoleSettings(loop, host, port, inputs)
