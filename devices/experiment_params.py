"""An experiment's parameters and the metrics it reports: the script's side of ``swarmdeck sweep``.

A script declares its parameters once, with their defaults, and reads them back::

    from swarmdeck.devices import params, record_metrics

    p = params(gain=1.0, spacing=0.3, label="ring")   # the defaults, or the sweep's values for this run
    ...
    record_metrics(error=float(err))                  # any time; the last value of each name counts

Run alone (``python script.py``, ``swarmdeck run script.py``) :func:`params` returns the defaults.
A runner overrides them through one environment variable, :data:`PARAMS_ENV`, holding a JSON
object ``{"gain": 0.5}`` (``swarmdeck sweep`` sets it inside each sandboxed run; ``swarmdeck run
--param gain=0.5`` sets it for one run). A name the script does not declare, or a value that does not
fit the default's type, is an error naming it and the declared names.

Defaults must be literals (``bool``, ``int``, ``float``, ``str``) written in the call, so a sweep reads the
declaration from the source without running the script (:func:`declared_in_source`).

:func:`record_metrics` hands values (finite numbers, names that are identifiers) to the run's sink —
in a sandboxed run the pipe to the trusted side, which checks them again (:func:`check_metrics`) and puts
them in the sweep's table; run alone, the values are checked and go nowhere (a script prints what it wants seen).
"""
from __future__ import annotations

import ast
import contextlib
import contextvars
import json
import math
import os
from collections.abc import Callable, Iterator, Mapping
from typing import Any

from swarmdeck.core.errors import SwarmdeckError

#: the environment variable a runner sets to a JSON object of parameter values
PARAMS_ENV = "SWARMDECK_PARAMS"
#: how many metrics a run may report, and the longest name (the trusted side's caps)
MAX_METRICS = 64
MAX_NAME = 64

Value = bool | int | float | str

#: where :func:`record_metrics` sends values in this run (None: nowhere); set by the sandbox's child
METRICS_SINK: contextvars.ContextVar[Callable[[dict[str, float]], None] | None] = contextvars.ContextVar(
    "swarmdeck_metrics_sink", default=None)  # noqa: B039  (a callable, never mutated)


class ParamError(ValueError, SwarmdeckError):
    """A parameter or metric that is not declared, or not of the declared kind."""


class Params(Mapping[str, Value]):
    """The run's parameter values (read-only): ``p.gain`` or ``p["gain"]``."""

    __slots__ = ("_values",)
    _values: dict[str, Value]

    def __init__(self, values: Mapping[str, Value]) -> None:
        object.__setattr__(self, "_values", dict(values))

    def __getattr__(self, name: str) -> Any:  # Any: ``p.gain * x`` reads as the script means it
        try:
            return self._values[name]
        except KeyError:
            raise AttributeError(f"no parameter {name!r} (declared: {', '.join(self._values) or 'none'})") from None

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError("parameters are read-only")

    def __getitem__(self, name: str) -> Value:
        return self._values[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)

    def __repr__(self) -> str:
        return "Params(" + ", ".join(f"{k}={v!r}" for k, v in self._values.items()) + ")"


def _check_default(name: str, value: Any) -> Value:
    if not name.isidentifier():
        raise ParamError(f"parameter name {name!r} is not an identifier")
    if isinstance(value, float) and not math.isfinite(value):
        raise ParamError(f"parameter {name}: the default must be finite, got {value!r}")
    if not isinstance(value, (bool, int, float, str)):
        raise ParamError(f"parameter {name}: the default must be a bool, int, float or str literal, "
                         f"got {type(value).__name__}")
    return value


def coerce(name: str, default: Value, value: Any) -> Value:
    """``value`` as the type of ``default`` (an int parameter takes 20.0 as 20, a float takes 2 as 2.0);
    ParamError naming the parameter when it does not fit."""
    if isinstance(default, bool):
        if isinstance(value, bool) or value in (0, 1):
            return bool(value)
    elif isinstance(default, int):
        if isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) \
                and float(value).is_integer():
            return int(value)
    elif isinstance(default, float):
        if isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value):
            return float(value)
    elif isinstance(value, str):
        return value
    raise ParamError(f"parameter {name} is a {type(default).__name__} (default {default!r}): "
                     f"cannot take {value!r}")


def overrides_from_env(environ: Mapping[str, str] | None = None) -> dict[str, Any]:
    """The values a runner set (:data:`PARAMS_ENV`), ``{}`` when none; ParamError for anything but a JSON object."""
    text = (os.environ if environ is None else environ).get(PARAMS_ENV)
    if not text:
        return {}
    try:
        data = json.loads(text)
    except ValueError as exc:
        raise ParamError(f"{PARAMS_ENV} is not JSON: {exc}") from None
    if not isinstance(data, dict):
        raise ParamError(f"{PARAMS_ENV} must be a JSON object of parameter values, got {type(data).__name__}")
    return data


def resolve(defaults: Mapping[str, Any], overrides: Mapping[str, Any]) -> dict[str, Value]:
    """The defaults with ``overrides`` applied; ParamError naming an undeclared name (and the declared ones)."""
    checked = {name: _check_default(name, value) for name, value in defaults.items()}
    unknown = [k for k in overrides if k not in checked]
    if unknown:
        raise ParamError(f"parameter{'s' if len(unknown) > 1 else ''} {', '.join(map(repr, unknown))} not declared "
                         f"by the script (it declares: {', '.join(checked) or 'none'})")
    return {name: coerce(name, d, overrides[name]) if name in overrides else d for name, d in checked.items()}


@contextlib.contextmanager
def params_in_environment(values: Mapping[str, Any] | None) -> Iterator[None]:
    """The script's parameter values in this process's environment (:data:`PARAMS_ENV`) while a script runs in it
    (``swarmdeck run --param``, a capsule's re-execution); the caller's environment given back after. None: left
    as it is."""
    if values is None:
        yield
        return
    saved = os.environ.get(PARAMS_ENV)
    os.environ[PARAMS_ENV] = json.dumps(dict(values))
    try:
        yield
    finally:
        if saved is None:
            os.environ.pop(PARAMS_ENV, None)
        else:
            os.environ[PARAMS_ENV] = saved


def params(**defaults: Value) -> Params:
    """Declare the script's parameters with their defaults; returns this run's values (the defaults when the
    script runs alone). ParamError when a runner sets a name not declared here or a value of another kind."""
    return Params(resolve(defaults, overrides_from_env()))


def check_metrics(values: Any) -> dict[str, float]:
    """``values`` as ``{name: float}``: a mapping of at most :data:`MAX_METRICS` identifier names (at most
    :data:`MAX_NAME` characters) to finite numbers; ParamError naming what is wrong."""
    if not isinstance(values, Mapping):
        raise ParamError(f"metrics must be a mapping of names to numbers, got {type(values).__name__}")
    if len(values) > MAX_METRICS:
        raise ParamError(f"at most {MAX_METRICS} metrics per run, got {len(values)}")
    out: dict[str, float] = {}
    for name, value in values.items():
        if not isinstance(name, str) or not name.isidentifier() or len(name) > MAX_NAME:
            raise ParamError(f"metric name {str(name)[:80]!r} must be an identifier of at most {MAX_NAME} characters")
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise ParamError(f"metric {name} must be a finite number, got {str(value)[:80]!r}")
        out[name] = float(value)
    return out


def record_metrics(**values: float) -> None:
    """Report metrics of this run (finite numbers): the sweep's table gets a column per name, the last value of
    each name counting. Call it as values become known — a run may end at its declared duration in any step.
    Run alone (no sweep collects them), the values are checked and kept nowhere."""
    checked = check_metrics(values)
    sink = METRICS_SINK.get()
    if sink is not None:
        sink(checked)


def _call_names(tree: ast.AST) -> tuple[set[str], set[str]]:
    """(names bound to :func:`params`, names bound to the module holding it) by the script's imports."""
    funcs: set[str] = set()
    modules = {"devices"}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module in ("swarmdeck.devices", "swarmdeck.devices.experiment_params"):
            funcs.update(a.asname or a.name for a in node.names if a.name == "params")
        elif isinstance(node, ast.ImportFrom) and node.module == "swarmdeck":
            modules.update(a.asname or a.name for a in node.names if a.name == "devices")
        elif isinstance(node, ast.Import):
            modules.update(a.asname for a in node.names if a.asname and a.name == "swarmdeck.devices")
    return funcs, modules


def declared_in_source(source: str, filename: str = "<script>") -> dict[str, Value] | None:
    """The parameters ``source`` declares with :func:`params` and their defaults, read without running it (None:
    it calls no ``params``). ParamError when a declaration is not of literal keyword defaults, or two differ;
    SyntaxError as :func:`compile` raises it."""
    tree = ast.parse(source, filename)
    funcs, modules = _call_names(tree)
    found: dict[str, Value] | None = None
    for node in ast.walk(tree):
        if not isinstance(node, ast.Call):
            continue
        f = node.func
        named = isinstance(f, ast.Name) and f.id in funcs
        dotted = (isinstance(f, ast.Attribute) and f.attr == "params"
                  and ((isinstance(f.value, ast.Name) and f.value.id in modules)
                       or (isinstance(f.value, ast.Attribute) and f.value.attr == "devices")))
        if not (named or dotted):
            continue
        where = f"{filename}:{node.lineno}"
        if node.args or any(k.arg is None for k in node.keywords):
            raise ParamError(f"{where}: params() takes keyword arguments only (name=default)")
        declared: dict[str, Value] = {}
        for k in node.keywords:
            try:
                value = ast.literal_eval(k.value)
            except ValueError:
                raise ParamError(f"{where}: the default of {k.arg} must be a literal (a number, bool or string) so "
                                 "a sweep can read it without running the script") from None
            declared[str(k.arg)] = _check_default(str(k.arg), value)
        if found is not None and found != declared:
            raise ParamError(f"{where}: params() is called twice with different declarations")
        found = declared
    return found
