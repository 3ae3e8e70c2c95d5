"""The robot models an arena can simulate, by name: the GRITSBot (default) and the GTernal (REFERENCE.md §1, §15).

A model is a :class:`~swarmdeck.core.kinematics.GritsBotParams` (drive and body); everything that moves or
checks robots takes one (``Arena(params=…)``, the simulator, the safety pipeline), so choosing a model is choosing
its params here. The Robotarium's Python simulator 2.x models GTernal robots (``rps/robotarium_abc.py``): the
same body diameter (0.11 m), wheel radius (0.016 m), top speed (0.2 m/s → 12.5 rad/s at the wheel) and collision
test (0.135 m, 0.025 m forward) as the GRITSBot, but a base length of 0.11 m instead of 0.105 m, so it turns a
little slower in place (2 r ω_max / L = 3.64 rad/s against 3.81 rad/s).

Chosen with ``[arena] robot_model = "gternal"`` in a run configuration, ``swarmdeck run --robot-model gternal``,
or ``robot_params("gternal")`` in code; the rps facade's 2.x ``Robotarium`` uses the GTernal unless told otherwise.

To add a model: one entry in :data:`ROBOT_MODELS` (its numbers in ``core/constants.py`` with their reference).
"""
from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType

from swarmdeck.core.constants import GTERNAL_BASE_LENGTH
from swarmdeck.core.kinematics import GritsBotParams

#: The default robot model of every arena (the console, ``swarmdeck run``, the 1.x rps facade).
DEFAULT_ROBOT_MODEL = "gritsbot"

#: Robot models by name → their drive and body (read-only).
ROBOT_MODELS: Mapping[str, GritsBotParams] = MappingProxyType({
    "gritsbot": GritsBotParams(),
    "gternal": GritsBotParams(axle_length=GTERNAL_BASE_LENGTH),
})


def robot_params(model: str) -> GritsBotParams:
    """The :class:`GritsBotParams` of robot model ``model`` (case-insensitive); a ValueError naming the
    model and the choices otherwise."""
    if not isinstance(model, str) or model.strip().lower() not in ROBOT_MODELS:
        raise ValueError(f"robot_model {model!r} is not a robot model swarmdeck simulates; "
                         f"choose one of {sorted(ROBOT_MODELS)}")
    return ROBOT_MODELS[model.strip().lower()]


def model_name(params: GritsBotParams) -> str | None:
    """The name of the model whose params are ``params`` (None for custom params)."""
    return next((name for name, p in ROBOT_MODELS.items() if p == params), None)
