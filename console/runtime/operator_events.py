"""Operator actions as typed events (DESIGN.md "Operator parameters"; issue 25 item 3).

Every change a person makes to a running loop — run, pause, step, emergency stop and its release,
a behaviour switch, behaviour / barrier / density parameters (the barrier on or off is
``SetSafety(enabled=False)``), density bumps added, dragged, edited or removed — is one frozen event
below. The loop (:class:`~swarmdeck.console.runtime.commands.OperatorCommands`) queues each event when
it takes effect and hands the queue to its operator listeners at the start of the tick that first
runs with it, stamped with that tick (:class:`Stamped`). The recorder writes them to
``/swarmdeck/operator`` and re-simulation replays them into a fresh loop before the same tick, so a
re-simulated run is driven by what the operator did, not by guesses from the recorded state.

Wire form (:func:`event_to_dict` / :func:`event_from_dict`): ``{"type": <class name>, <fields>}``;
parameter changes carry ``[[name, value], ...]`` and are converted back by the parameters'
declarations (:mod:`swarmdeck.console.runtime.params`).
"""
from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from swarmdeck.console.runtime import params as P

Changes = tuple[tuple[str, Any], ...]


@dataclass(frozen=True)
class OperatorEvent:
    """Base of the operator's actions."""


@dataclass(frozen=True)
class Run(OperatorEvent):
    """Resume (robots move every tick)."""


@dataclass(frozen=True)
class Pause(OperatorEvent):
    """Robots hold still until Run or Step."""


@dataclass(frozen=True)
class Step(OperatorEvent):
    """While paused: ``n`` more ticks with motion."""

    n: int = 1


@dataclass(frozen=True)
class EStop(OperatorEvent):
    """Emergency stop: every command zero until released."""


@dataclass(frozen=True)
class Release(OperatorEvent):
    """Release the emergency stop (the loop stays paused)."""


@dataclass(frozen=True)
class SwitchBehaviour(OperatorEvent):
    """Switch to behaviour ``name`` (``coverage``, ``goto``, ``script:PATH``, …)."""

    name: str


@dataclass(frozen=True)
class _SetGroup(OperatorEvent):
    """Changes ``((field, value), ...)`` to one parameter class (:attr:`group`)."""

    changes: Changes
    group: ClassVar[type] = object

    def as_kwargs(self) -> dict[str, Any]:
        """The changes as keyword arguments, each value converted to its declared type (JSON lists → tuples)."""
        conv = P.converters(self.group)
        return {k: conv[k](v) if k in conv else v for k, v in self.changes}


@dataclass(frozen=True)
class SetParams(_SetGroup):
    """Behaviour parameters changed (:class:`~swarmdeck.console.runtime.params.BehaviourParams`)."""

    group: ClassVar[type] = P.BehaviourParams


@dataclass(frozen=True)
class SetSafety(_SetGroup):
    """Barrier parameters changed, or the barrier switched on or off
    (:class:`~swarmdeck.console.runtime.params.SafetyParams`)."""

    group: ClassVar[type] = P.SafetyParams


@dataclass(frozen=True)
class SetDensity(_SetGroup):
    """Density parameters changed (:class:`~swarmdeck.console.runtime.params.DensityParams`)."""

    group: ClassVar[type] = P.DensityParams


@dataclass(frozen=True)
class AddBump(OperatorEvent):
    """Bump ``bid`` painted at (x, y) m with σ (m) and weight, at run time ``t`` (s)."""

    bid: int
    x: float
    y: float
    sigma: float
    weight: float
    t: float


@dataclass(frozen=True)
class MoveBump(OperatorEvent):
    """Bump ``bid`` dragged to (x, y) m at run time ``t`` (s)."""

    bid: int
    x: float
    y: float
    t: float


@dataclass(frozen=True)
class UpdateBump(OperatorEvent):
    """Bump ``bid``'s σ (m) and/or weight changed (None: unchanged)."""

    bid: int
    sigma: float | None = None
    weight: float | None = None


@dataclass(frozen=True)
class RemoveBump(OperatorEvent):
    """Bump ``bid`` starts fading out at run time ``t`` (s)."""

    bid: int
    t: float


@dataclass(frozen=True)
class Stamped:
    """An event with the tick (index) that first ran with it and that tick's loop clock ``time`` (s)."""

    tick: int
    time: float
    event: OperatorEvent


EVENT_TYPES: dict[str, type[OperatorEvent]] = {cls.__name__: cls for cls in (
    Run, Pause, Step, EStop, Release, SwitchBehaviour, SetParams, SetSafety, SetDensity,
    AddBump, MoveBump, UpdateBump, RemoveBump)}


def changes_of(params: Any, names: Any) -> Changes:
    """The changes to ``names`` as an event carries them: the validated values of the new ``params``."""
    return tuple((str(k), getattr(params, k)) for k in names)


def _plain(v: Any) -> Any:
    """JSON-native: tuples, lists and arrays as lists, numpy scalars as Python numbers."""
    if isinstance(v, (tuple, list, np.ndarray)):
        return [_plain(x) for x in v]
    if isinstance(v, np.generic):
        return v.item()
    return v


def event_to_dict(stamped: Stamped) -> dict[str, Any]:
    """The recorded form: ``{"tick", "time", "type", <fields>}`` (JSON-able)."""
    e = stamped.event
    out: dict[str, Any] = {"tick": stamped.tick, "time": stamped.time, "type": type(e).__name__}
    for f in dataclasses.fields(e):
        out[f.name] = _plain(getattr(e, f.name))
    return out


def event_from_dict(d: Mapping[str, Any]) -> Stamped:
    """Inverse of :func:`event_to_dict`; ValueError naming what is wrong (an unknown type, a bad field)."""
    try:
        cls = EVENT_TYPES[str(d["type"])]
        kw = {f.name: d[f.name] for f in dataclasses.fields(cls) if f.name in d}
        if "changes" in kw:
            kw["changes"] = tuple((str(k), v) for k, v in kw["changes"])
        return Stamped(int(d["tick"]), float(d["time"]), cls(**kw))
    except KeyError as exc:
        raise ValueError(f"operator event without {exc}: {dict(d)!r}") from None
    except (TypeError, ValueError) as exc:
        raise ValueError(f"unreadable operator event {dict(d)!r}: {exc}") from None
