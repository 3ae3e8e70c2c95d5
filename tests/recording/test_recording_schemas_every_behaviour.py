"""Every message of every channel validates against the schema its channel carries — for every behaviour
(coverage, rendezvous, formation, goto, a ``script:`` behaviour, a failing script) and for learning-env
episodes of every task, not just coverage: JSON channels against their embedded JSON Schema, Foxglove's
protobuf channels against the SDK descriptor beside them."""
from __future__ import annotations

import json

import jsonschema
import pytest
from foxglove_schemas import decode
from mcap.reader import make_reader

import swarmdeck.envs as envs
from swarmdeck.console.recording.episodes import record_episodes
from swarmdeck.console.recording.recorder import Recorder
from swarmdeck.console.recording.schemas import TOPIC_FRAME
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig

SCRIPT = "import numpy as np\ndef behaviour(poses, t):\n    return np.tile([0.05, 0.0], (len(poses), 1))\n"
FAILING = "def behaviour(poses, t):\n    raise ValueError('no')\n"


def validate_every_message(path) -> dict[str, int]:
    """Validate every message of the file against its channel's schema; returns messages per topic."""
    counts: dict[str, int] = {}
    validators: dict[int, jsonschema.Draft202012Validator] = {}
    with open(path, "rb") as fh:
        for schema, channel, msg in make_reader(fh).iter_messages():
            if schema.encoding == "jsonschema":
                if schema.id not in validators:
                    declared = json.loads(schema.data)
                    jsonschema.Draft202012Validator.check_schema(declared)
                    validators[schema.id] = jsonschema.Draft202012Validator(declared)
                errors = [e.message for e in validators[schema.id].iter_errors(json.loads(msg.data))]
                assert not errors, f"{channel.topic}: {errors[:3]}"
            else:
                assert schema.encoding == "protobuf", (channel.topic, schema.encoding)
                decode(schema.name, schema.data, msg.data)
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
    return counts


@pytest.mark.parametrize("behaviour", ["coverage", "rendezvous", "formation", "goto", "decentralised", "script",
                                       "failing script"])
def test_a_console_session_of_every_behaviour_conforms(tmp_path, behaviour):
    name = behaviour
    if behaviour.endswith("script"):
        script = tmp_path / "b.py"
        script.write_text(FAILING if behaviour.startswith("failing") else SCRIPT)
        name = f"script:{script}"
    loop = ControlLoop(LoopConfig(n_robots=5, seed=2, behaviour=name, script_budget=0.5))
    path = tmp_path / "s.mcap"
    with Recorder(path, {"config": {"behaviour": name}}) as rec:
        for k in range(6):
            if k == 3:
                loop.set_safety(enabled=False)  # a barrier record of the guard too
            rec.write_frame(loop.tick())
    loop.close()
    counts = validate_every_message(path)
    assert counts[TOPIC_FRAME] == 6 and "/foxglove/robots" in counts
    assert ("/foxglove/network" in counts) == (behaviour == "decentralised")  # its links, validated too


@pytest.mark.parametrize("task", envs.TASKS)
def test_learning_episodes_of_every_task_conform(tmp_path, task):
    env = record_episodes(envs.parallel_env(n_robots=4, task=task, max_steps=5), tmp_path)
    env.reset(seed=0)
    while env.agents:
        env.step({a: env.action_space(a).sample() for a in env.agents})
    env.close()
    (path,) = env.paths
    assert validate_every_message(path)[TOPIC_FRAME] == 5
