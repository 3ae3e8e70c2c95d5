"""The console's TOML configuration file (``swarmdeck console --config FILE``).

Tables (every key optional; defaults from REFERENCE.md)::

    [console]   host = "127.0.0.1", port = 8080, robots = 12, behaviour = "coverage",
                seed = 1, dt = 0.033, max_speed = 0.2, bounds = [-1.6, 1.6, -1.0, 1.0],
                script_budget = dt / 2 (s a script: behaviour may take per tick),
                foxglove_channels = true (false: recordings carry only swarmdeck's own channels),
                coverage_worker = "auto" ("on" | "off": coverage two ticks behind on two worker threads;
                auto: from 2000 robots; console/runtime/coverage_worker.py)
                (or arena = "10x6" instead of bounds: a W x H m arena centred on the origin)
    [behaviour] kappa, law, gain, formation_edge, formation_gain, goals = [[x, y], ...],
                goal_centre = [x, y]
    [safety]    enabled, safety_distance, gamma, class_k, mode ("auto" | "centralised" | "distributed")
    [density]   moving, radius, period, sigma, weight, floor, bump_sigma, bump_weight
    [inputs]    see swarmdeck.inputs.InputConfig (listeners, density, bounds)
    [arena]     obstacles = [[[x0, y0], [x1, y1]], {polygon = [[x, y], ...]}, {polyline = [[x, y], ...]}]
                (line-segment obstacles, m: solid in the simulator, kept clear by the barrier; core.obstacles)
    [arena]     robot_model = "gritsbot" (or "gternal": Robotarium 2.x's robot, base length 0.11 m;
                swarmdeck.core.robot_models)
    [recording] foxglove_channels = true (as in [console]; give it in one table), chunk_frames = 20
                (frames per MCAP chunk, each chunk starts with a keyframe: ≈ 0.67 s at 30 Hz), robot_rate = 1000 (robots per
                second the per-robot Foxglove scene channels carry: N = 100 → 10 scenes/s, N = 1000 → 1),
                packed = true (the robots as one packed PointCloud, /foxglove/robot_points; false: a disc,
                an arrow and a label per robot), lines_period = 1 (s between the Voronoi-edge and
                barrier-pair scenes; 0: with the robots')

The keys of ``[behaviour]``, ``[safety]``, ``[density]`` and the loop's keys of ``[console]`` are the
operator parameters declared in :mod:`swarmdeck.console.runtime.params` (units, ranges and defaults
there; the list above is a summary). Unknown tables or keys and values out of range are errors naming
the table and key.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from swarmdeck.console.runtime.params import (
    BehaviourParams,
    DensityParams,
    LoopConfig,
    SafetyParams,
    converters,
    toml_keys,
)
from swarmdeck.core.checks import in_range
from swarmdeck.core.config import ConfigError, check_keys, from_mapping, read_toml
from swarmdeck.core.obstacles import ObstacleError, Obstacles
from swarmdeck.core.robot_models import DEFAULT_ROBOT_MODEL, robot_params

TABLES = ("console", "behaviour", "safety", "density", "inputs", "recording", "arena")
ARENA_KEYS = ("obstacles", "robot_model")
RECORDING_KEYS = ("foxglove_channels", "chunk_frames", "robot_rate", "packed", "lines_period")
# [console] key -> LoopConfig field (errors name the key, not the field), from the parameters' declarations
LOOP_KEYS = toml_keys(LoopConfig)
CONSOLE_KEYS = ("host", "port", *LOOP_KEYS, "arena", "foxglove_channels")


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


class ConfigFileError(ConfigError):
    """A configuration file that cannot be used; the message names the file, table and key."""

_UNKNOWN = "unknown key(s) {unknown} in {what}; expected some of {known}"


@dataclass(frozen=True)
class ConsoleSettings:
    """What the file says: the loop's config, server address, the raw ``[inputs]`` table (or None), and
    whether recordings carry Foxglove's channels (``foxglove_channels``), the recorder's chunking
    (``chunk_frames``) and the Foxglove channels' ``robot_rate``, ``packed``, ``lines_period`` (``[recording]``), and the
    simulated robots' model (``[arena] robot_model``, :mod:`swarmdeck.core.robot_models`)."""

    loop: LoopConfig
    host: str = "127.0.0.1"
    port: int = 8080
    inputs: dict | None = None
    foxglove_channels: bool = True
    chunk_frames: int = 20
    robot_rate: float = 1000.0
    packed: bool = True
    lines_period: float = 1.0
    robot_model: str = DEFAULT_ROBOT_MODEL


def _build(cls: type, doc: dict, name: str, path: Path, convert: dict[str, Any] | None = None) -> Any:
    return from_mapping(cls, doc.get(name, {}), f"[{name}]", convert=convert, error=ConfigFileError,
                        template=_UNKNOWN, source=path)


def _arena_table(doc: dict, path: Path) -> dict[str, Any]:
    """The ``[arena]`` table's LoopConfig fields: ``obstacles`` as :class:`~swarmdeck.core.obstacles.Obstacles`
    (ConfigFileError naming the file, the key and the segment otherwise)."""
    arena = check_keys(doc.get("arena", {}), ARENA_KEYS, "[arena]", error=ConfigFileError, template=_UNKNOWN,
                       source=path)
    if "obstacles" not in arena:
        return {}
    try:
        return {"obstacles": Obstacles.from_config(arena["obstacles"])}
    except ValueError as exc:
        raise ConfigFileError(f"{path}: [arena] obstacles: {exc}") from None


def read_obstacles(path: str | Path) -> Obstacles | None:
    """The ``[arena] obstacles`` of TOML file ``path`` (other tables are ignored: a console config works), None
    when it has none; ConfigFileError naming the file, the key and the segment otherwise (``swarmdeck run
    --obstacles``). The segments are checked against the arena's bounds where the Arena is built."""
    p = Path(path)
    doc = read_toml(p, ConfigFileError)
    return _arena_table(doc, p).get("obstacles")


def load_settings(path: str | Path) -> ConsoleSettings:
    """Read and validate a console configuration file."""
    p = Path(path)
    doc = read_toml(p, ConfigFileError)
    check_keys(doc, TABLES, "the file", error=ConfigFileError, source=p,
               template="unknown table(s) {unknown}; expected some of {known}")
    con = check_keys(doc.get("console", {}), CONSOLE_KEYS, "[console]", error=ConfigFileError, template=_UNKNOWN,
                     source=p)
    bp = _build(BehaviourParams, doc, "behaviour", p, converters(BehaviourParams))
    sp = _build(SafetyParams, doc, "safety", p, converters(SafetyParams))
    dp = _build(DensityParams, doc, "density", p, converters(DensityParams))
    convert = converters(LoopConfig)
    loop_kw: dict[str, Any] = {"behaviour_params": bp, "safety": sp, "density": dp}
    loop_kw.update(_arena_table(doc, p))
    for key, target in LOOP_KEYS.items():  # one key at a time, so the error names the key written
        if key not in con:
            continue
        try:
            value = convert[target](con[key]) if target in convert else con[key]
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
    except ObstacleError as exc:  # the segments against the arena's bounds
        raise ConfigFileError(f"{p}: [arena] obstacles: {exc}") from None
    except (TypeError, ValueError) as exc:
        raise ConfigFileError(f"{p}: [console]: {exc}") from None
    host = con.get("host", "127.0.0.1")
    port = con.get("port", 8080)
    if not isinstance(host, str) or not host:
        raise ConfigFileError(f"{p}: [console] host must be a non-empty string, got {host!r}")
    if not in_range(port, 0, 65535, integer=True):
        raise ConfigFileError(f"{p}: [console] port must be an integer in [0, 65535], got {port!r}")
    rec = check_keys(doc.get("recording", {}), RECORDING_KEYS, "[recording]", error=ConfigFileError,
                     template=_UNKNOWN, source=p)
    if "foxglove_channels" in con and "foxglove_channels" in rec:
        raise ConfigFileError(f"{p}: foxglove_channels is in [console] and [recording]; give it once")
    where = "recording" if "foxglove_channels" in rec else "console"
    fox = rec.get("foxglove_channels", con.get("foxglove_channels", True))
    if not isinstance(fox, bool):
        raise ConfigFileError(f"{p}: [{where}] foxglove_channels must be true or false, got {fox!r}")
    chunk_frames = rec.get("chunk_frames", ConsoleSettings.chunk_frames)
    if isinstance(chunk_frames, bool) or not in_range(chunk_frames, 1, 1_000_000, integer=True):
        raise ConfigFileError(f"{p}: [recording] chunk_frames must be an integer >= 1 (frames), got {chunk_frames!r}")
    robot_rate = rec.get("robot_rate", ConsoleSettings.robot_rate)
    if isinstance(robot_rate, bool) or not in_range(robot_rate, 0, 1e9):
        raise ConfigFileError(f"{p}: [recording] robot_rate must be a number >= 0 (robots/s; 0: every frame), "
                              f"got {robot_rate!r}")
    inputs = doc.get("inputs")
    if inputs is not None and not isinstance(inputs, dict):
        raise ConfigFileError(f"{p}: [inputs] must be a table")
    packed = rec.get("packed", ConsoleSettings.packed)
    if not isinstance(packed, bool):
        raise ConfigFileError(f"{p}: [recording] packed must be true or false, got {packed!r}")
    lines_period = rec.get("lines_period", ConsoleSettings.lines_period)
    if isinstance(lines_period, bool) or not in_range(lines_period, 0, 1e6):
        raise ConfigFileError(f"{p}: [recording] lines_period must be a number >= 0 (s), got {lines_period!r}")
    return ConsoleSettings(loop, host, port, inputs, fox, int(chunk_frames), float(robot_rate), packed,
                           float(lines_period), _robot_model(doc, p))


def _robot_model(doc: dict, path: Path) -> str:
    """``[arena] robot_model``: a name of :data:`~swarmdeck.core.robot_models.ROBOT_MODELS` (default the GRITSBot)."""
    arena = check_keys(doc.get("arena", {}), ARENA_KEYS, "[arena]", error=ConfigFileError, template=_UNKNOWN,
                       source=path)
    model = arena.get("robot_model", DEFAULT_ROBOT_MODEL)
    try:
        robot_params(model)
    except ValueError as exc:
        raise ConfigFileError(f"{path}: [arena] {exc}") from None
    return str(model).strip().lower()
