"""Each operator parameter is declared once (console/runtime/params.py) and everything is generated from it:
validation, TOML keys and conversion, GUI widgets, Frame.params and the recording's config."""
from __future__ import annotations

import dataclasses

import pytest

from swarmdeck.console.runtime import params
from swarmdeck.console.runtime.config import LOOP_KEYS, ConfigFileError, load_settings
from swarmdeck.console.runtime.params import (
    BehaviourParams,
    DensityParams,
    LoopConfig,
    SafetyParams,
    check_params,
    converters,
    frame_keys,
    frame_params,
    from_dict,
    gui_fields,
    param,
    specs,
    to_dict,
    toml_keys,
)

GROUPS = (BehaviourParams, SafetyParams, DensityParams, LoopConfig)


def test_frame_params_keep_their_recorded_keys_and_order() -> None:
    got = frame_params(BehaviourParams(), SafetyParams(), DensityParams(), LoopConfig())
    assert list(got) == ["kappa", "law", "gain", "formation_edge", "formation_gain", "safety_enabled",
                         "safety_distance", "gamma", "class_k", "barrier_mode", "moving_density", "max_speed"]
    assert got["safety_enabled"] is True and got["safety_distance"] == 0.17 and got["gamma"] == 100.0
    assert frame_keys(SafetyParams)["barrier_mode"] == "mode"


@pytest.mark.parametrize("cls", GROUPS)
def test_every_range_is_checked_with_its_name(cls: type) -> None:
    for name, spec in specs(cls):
        if spec.hi is not None and spec.hi != float("inf"):
            with pytest.raises(ValueError, match=name.split("_")[0]):
                cls(**{name: spec.hi * 2 + 1})
        if spec.choices is not None:
            with pytest.raises(ValueError, match="must be one of"):
                cls(**{name: "no-such-choice"})


def test_the_console_table_keys_come_from_the_declaration() -> None:
    assert LOOP_KEYS == toml_keys(LoopConfig)
    assert LOOP_KEYS["robots"] == "n_robots" and "dt" in LOOP_KEYS and "behaviour_params" not in LOOP_KEYS


def test_toml_whole_numbers_and_arrays_convert_by_declared_type(tmp_path) -> None:
    f = tmp_path / "c.toml"
    f.write_text("[console]\nrobots = 5\nbounds = [-2, 2, -1, 1]\n[behaviour]\nkappa = 2\ngoal_centre = [0, 1]\n"
                 "[safety]\ngamma = 50\n[density]\nbump_sigma = 0.3\n")
    s = load_settings(f)
    assert s.loop.n_robots == 5 and s.loop.bounds == (-2.0, 2.0, -1.0, 1.0)
    assert s.loop.behaviour_params.kappa == 2.0 and isinstance(s.loop.behaviour_params.kappa, float)
    assert s.loop.behaviour_params.goal_centre == (0.0, 1.0) and s.loop.safety.gamma == 50.0
    f.write_text("[safety]\ngamma = 5000\n")
    with pytest.raises(ConfigFileError, match="gamma"):
        load_settings(f)


def test_the_recorded_config_round_trips() -> None:
    cfg = LoopConfig(n_robots=7, seed=3, bounds=(-2.0, 2.0, -1.0, 1.0), script_budget=0.01,
                     behaviour_params=BehaviourParams(kappa=2.0, goals=((0.1, 0.2), (0.3, 0.4))),
                     safety=SafetyParams(gamma=20.0, class_k="linear"), density=DensityParams(moving=False))
    d = to_dict(cfg)
    assert d["behaviour_params"]["goals"] == [[0.1, 0.2], [0.3, 0.4]] and d["bounds"] == [-2.0, 2.0, -1.0, 1.0]
    assert from_dict(LoopConfig, d) == cfg
    d["bounds"] = [-2, 2, -1, 1]  # whole numbers in JSON come back as floats
    assert from_dict(LoopConfig, d).bounds == (-2.0, 2.0, -1.0, 1.0)


def test_gui_widgets_are_the_labelled_parameters() -> None:
    assert [n for n, _ in gui_fields(BehaviourParams)] == ["kappa", "law", "gain", "formation_edge"]
    assert [n for n, _ in gui_fields(SafetyParams)] == ["enabled", "safety_distance", "gamma", "class_k"]
    d_s = dict(gui_fields(SafetyParams))["safety_distance"]
    assert (d_s.lo, d_s.hi, d_s.unit) == (0.11, 0.4, "m")


def test_a_new_parameter_needs_one_line() -> None:
    """What a newcomer writes: one field. Validation, TOML conversion, GUI, Frame and recording follow."""

    @dataclasses.dataclass(frozen=True)
    class Demo:
        spin: float = param(0.5, unit="rad/s", lo=0.0, hi=2.0, label="Spin (rad/s)", step=0.1, frame="spin")

        def __post_init__(self) -> None:
            check_params(self)

    with pytest.raises(ValueError, match=r"spin must be in \[0, 2\] rad/s"):
        Demo(spin=3.0)
    assert converters(Demo)["spin"](1) == 1.0
    assert [n for n, _ in gui_fields(Demo)] == ["spin"]
    assert frame_params(Demo()) == {"spin": 0.5} and frame_keys(Demo) == {"spin": "spin"}
    assert from_dict(Demo, to_dict(Demo(spin=1.5))) == Demo(spin=1.5)
    assert params.toml_keys(Demo) == {"spin": "spin"}
