"""A policy file (swarmdeck.envs.policy) is untrusted input: plain arrays only (never a pickle), every array
checked, a clear error naming the file and the problem; a good one round-trips and acts as its weights say."""
from __future__ import annotations

import io
import json
import pickle

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.devices import Arena
from swarmdeck.envs.deploy import drive, experiment_script, scenario_for
from swarmdeck.envs.policy import PolicyError, load_policy, make_policy, policy_arrays, save_policy
from swarmdeck.envs.scenarios import make_scenario

D = make_scenario("rendezvous", n_agents=3).obs_size


def _layers(rng, sizes):
    return [(rng.normal(size=(a, b)), rng.normal(size=b)) for a, b in zip(sizes[:-1], sizes[1:])]


def _policy(rng=None, action="velocity", out=2):
    rng = rng or np.random.default_rng(0)
    return make_policy(_layers(rng, [D, 8, out]), scenario="rendezvous", scenario_args={"n_agents": 3},
                       action=action, action_low=[-0.2, -0.2], action_high=[0.2, 0.2], trained={"steps": 1})


def _arrays(policy):
    return policy_arrays(policy)


def _bytes(arrays) -> bytes:
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    return buf.getvalue()


def test_a_policy_round_trips_and_acts_as_its_weights_say(tmp_path):
    p = _policy()
    q = load_policy(save_policy(p, tmp_path / "policy.npz"))
    assert q.meta == p.meta and q.obs_size == D and len(q.layers) == 2
    obs = np.random.default_rng(1).normal(size=(3, D))
    (w0, b0), (w1, b1) = q.layers
    expected = np.clip(np.tanh(obs @ w0 + b0) @ w1 + b1, -0.2, 0.2)
    np.testing.assert_allclose(q.act(obs), expected)
    np.testing.assert_allclose(q.act(obs), p.act(obs), atol=1e-5)  # float32 on disk
    moves = load_policy(_bytes(_arrays(_policy(action="moves", out=5))))
    assert moves.act(obs).dtype == np.int64 and set(moves.act(obs).tolist()) <= set(range(5))
    with pytest.raises(ValueError, match=rf"shape \(N, {D}\)"):
        q.act(np.zeros((3, D + 1)))


def _mutated(**change):
    arrays = _arrays(_policy())
    for key, value in change.items():
        if value is None:
            arrays.pop(key)
        else:
            arrays[key] = value
    return _bytes(arrays)


def _meta(**change):
    meta = json.loads(str(_arrays(_policy())["meta"]))
    meta.update(change)
    return np.array(json.dumps(meta))


@pytest.mark.parametrize(("data", "message"), [
    (b"not a zip at all", "not a numpy .npz"),
    (pickle.dumps({"w0": 1}), "not a numpy .npz"),
    (_mutated(meta=None), "no 'meta' array"),
    (_mutated(meta=np.array("{not json")), "'meta' is not valid JSON"),
    (_mutated(meta=np.array([1.0, 2.0])), "'meta' must be a 0-d string array"),
    (_mutated(meta=_meta(version=7)), "version 7 is not supported"),
    (_mutated(meta=_meta(format="other")), "format is 'other'"),
    (_mutated(meta=_meta(activation="sigmoid")), "activation must be one of"),
    (_mutated(meta=_meta(action="fly")), "action must be one of"),
    (_mutated(meta=_meta(action_low=[0.0])), "'action_low' must be a list of 2 finite numbers"),
    (_mutated(meta=_meta(scenario_args={"n_agents": [1, 2]})), "'scenario_args' must be an object"),
    (_mutated(w1=None), "the layers must be w0, b0"),
    (_mutated(extra=np.zeros(2)), "unexpected array 'extra'"),
    (_mutated(w0=np.zeros((D, 8), dtype=np.int64)), "w0 must be float32 or float64, got int64"),
    (_mutated(w0=np.full((D, 8), np.nan)), "w0 holds NaN or inf"),
    (_mutated(w0=np.zeros(D)), "w0 must be a non-empty 2-D array"),
    (_mutated(w1=np.zeros((9, 2))), "w1 takes 9 inputs but layer 0 gives 8"),
    (_mutated(b0=np.zeros(3)), r"b0 must have shape \(8,\)"),
    (_mutated(w1=np.zeros((8, 5)), b1=np.zeros(5)), "the last layer gives 5 numbers; a velocity policy gives 2"),
], ids=lambda v: v if isinstance(v, str) else None)
def test_a_malformed_policy_file_is_refused_naming_the_problem(tmp_path, data, message):
    path = tmp_path / "policy.npz"
    path.write_bytes(data)
    with pytest.raises(PolicyError, match=message) as err:
        load_policy(path)
    assert "policy.npz" in str(err.value)


def test_too_many_parameters_are_refused(tmp_path, monkeypatch):
    import swarmdeck.envs.policy as policy_module

    path = save_policy(_policy(), tmp_path / "big.npz")
    monkeypatch.setattr(policy_module, "MAX_PARAMETERS", 20)
    with pytest.raises(PolicyError, match="more than 20 parameters"):
        load_policy(path)


def test_a_compressed_file_that_inflates_past_the_limit_is_refused_before_it_is_read(tmp_path):
    path = tmp_path / "bomb.npz"
    arrays = _arrays(_policy())
    arrays["w0"] = np.zeros((D, 1 << 17))  # 15 MB of zeros, a few kB compressed
    np.savez_compressed(path, **arrays)
    assert path.stat().st_size < 1 << 20
    with pytest.raises(PolicyError, match="inflates to .* bytes, more than the limit"):
        load_policy(path)


def test_an_object_array_is_never_unpickled(tmp_path):
    path = tmp_path / "evil.npz"
    arrays = _arrays(_policy())
    arrays["w0"] = np.array([{"__reduce__": "boom"}], dtype=object)
    np.savez(path, **arrays)  # writing an object array pickles it; reading it must refuse
    with pytest.raises(PolicyError, match="not a numpy .npz of plain arrays"):
        load_policy(path)


def test_a_missing_file_and_a_single_npy_are_named(tmp_path):
    with pytest.raises(PolicyError, match="cannot read policy file"):
        load_policy(tmp_path / "absent.npz")
    np.save(tmp_path / "one.npy", np.zeros(3))
    with pytest.raises(PolicyError, match="single .npy array"):
        load_policy(tmp_path / "one.npy")


@settings(max_examples=40)
@given(st.binary(max_size=600))
def test_any_bytes_give_a_policy_error_or_a_policy(data):
    try:
        load_policy(data)
    except PolicyError:
        pass


def test_a_policy_for_another_observation_size_is_refused_before_the_run():
    p = make_policy(_layers(np.random.default_rng(0), [D + 2, 4, 2]), scenario="rendezvous",
                    scenario_args={"n_agents": 3}, action="velocity", action_low=[-0.2, -0.2], action_high=[0.2, 0.2])
    with pytest.raises(ValueError, match=f"takes observations of {D + 2} numbers"):
        scenario_for(p, 3)
    unknown = make_policy(_layers(np.random.default_rng(0), [D, 4, 2]), scenario="soccer", scenario_args={},
                          action="velocity", action_low=[-0.2, -0.2], action_high=[0.2, 0.2])
    with pytest.raises(ValueError, match="unknown scenario 'soccer'"):
        scenario_for(unknown, 3)


def test_drive_runs_a_policy_inside_the_barrier_for_the_arenas_duration():
    arena = Arena(3, duration=0.5)
    out = drive(arena, _policy())
    assert out["policy steps"] >= 1 and np.isfinite(out["mean reward per agent and step"])
    report = arena.report().to_dict()
    assert report["safety"]["enabled"] and report["safety"]["calls"] >= out["policy steps"]
    assert report["safety"]["failures"] == 0


def test_the_experiment_script_keeps_a_policy_files_words_out_of_its_code():
    p = make_policy(_layers(np.random.default_rng(0), [D, 4, 2]), scenario="rendezvous", scenario_args={"n_agents": 3},
                    action="velocity", action_low=[-0.2, -0.2], action_high=[0.2, 0.2],
                    trained={"library": '"""\nimport os; os.system("x")\n"""'})
    script = experiment_script(p, 3, 5.0)
    compile(script, "main.py", "exec")
    assert script.count('"""') == experiment_script(_policy(), 3, 5.0).count('"""')
    assert not any(line.startswith("import os") for line in script.splitlines())
    assert '"x"' not in script  # the quotes are gone: the words stay inside the docstring
