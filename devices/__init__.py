"""swarmdeck.devices: the simulated arena and the experiment API (the GRITSBot's model is
:mod:`swarmdeck.core.kinematics`, re-exported here for experiments).

The :class:`Arena` is what experiments program against, at any abstraction
level of the paper (wheel speeds, unicycle, single integrator, go-to-goal,
waypoints, next positions); it drives robot ports (:mod:`swarmdeck.core.ports`) through
:class:`SteppedRobots`: :class:`SimulatedRobots` over the physics (:class:`SimulatedArena`) by
default, ``NetworkRobots`` for GRITSBots over MQTT.
"""
from swarmdeck.core.kinematics import (
    GritsBotParams,
    limit_unicycle,
    lookahead_points,
    saturate,
    si_to_unicycle,
    unicycle_step,
    unicycle_to_si,
    unicycle_to_wheels,
    wheel_scale,
    wheels_to_unicycle,
    wrap_angle,
)
from swarmdeck.devices.arena import RUN_DEFAULTS, Arena, ArenaReport, ExperimentFinished, RunDefaults
from swarmdeck.devices.controllers import (
    HybridPoseController,
    at_pose,
    at_position,
    clf_unicycle_pose_controller,
    clf_unicycle_position_controller,
    si_position_controller,
)
from swarmdeck.devices.experiment_params import params, record_metrics
from swarmdeck.devices.initial_conditions import max_robots, random_initial_poses
from swarmdeck.devices.simulated_robots import SimulatedRobots
from swarmdeck.devices.simulator import ArenaConfig, SimulatedArena
from swarmdeck.devices.stepped import SteppedRobots
from swarmdeck.devices.validation import ValidationReport, ValidationRules, colliding_pairs, out_of_bounds

# Transports load paho-mqtt; import them on first use so `import swarmdeck.devices` stays light.
_LAZY = {
    "RobotTransport": "net.transport",
    "InProcessTransport": "net.transport_inprocess",
    "MqttTransport": "net.transport_mqtt",
    "CommandStreamer": "net.streamer",
    "NetworkRobots": "net.console_robots",
    "parse_broker_url": "net.mqtt_config",
    "MqttConfig": "net.mqtt_config",
}


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(f"{__name__}.{_LAZY[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [*_LAZY,  # noqa: PLE0604  (the lazily imported names)
    "Arena", "ArenaConfig", "ArenaReport", "ExperimentFinished", "GritsBotParams", "HybridPoseController",
    "RunDefaults", "RUN_DEFAULTS", "SimulatedArena", "SimulatedRobots", "SteppedRobots", "ValidationReport", "ValidationRules",
    "at_pose", "at_position", "clf_unicycle_pose_controller", "clf_unicycle_position_controller",
    "colliding_pairs", "limit_unicycle", "lookahead_points", "max_robots", "out_of_bounds", "params",
    "random_initial_poses", "record_metrics", "saturate", "si_position_controller", "si_to_unicycle", "unicycle_step",
    "unicycle_to_si", "unicycle_to_wheels", "wheel_scale", "wheels_to_unicycle", "wrap_angle",
]
