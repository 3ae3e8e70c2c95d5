"""One config helper: mapping → frozen dataclass, unknown keys refused, bad values named with key and file."""
import math
from dataclasses import dataclass

import numpy as np
import pytest

from swarmdeck.core.checks import in_range, require_in_range
from swarmdeck.core.config import ConfigError, check_keys, floats, from_mapping, read_toml


@dataclass(frozen=True)
class Inner:
    gain: float = 1.0

    def __post_init__(self) -> None:
        require_in_range(self.gain, "gain", 0.0, 5.0, lo_open=True)


@dataclass(frozen=True)
class Outer:
    name: str = "a"
    bounds: tuple[float, ...] = (0.0, 1.0)
    inner: Inner = Inner()


def build(data, source=None):
    return from_mapping(Outer, data, "[outer]", source=source,
                        convert={"bounds": floats, "inner": lambda t: from_mapping(Inner, t, "[outer.inner]")})


def test_values_converted_and_checked():
    cfg = build({"bounds": [1, 2], "inner": {"gain": 2}})
    assert cfg == Outer(bounds=(1.0, 2.0), inner=Inner(2))


@pytest.mark.parametrize("data, words", [
    ({"nmae": "x"}, "unknown [outer] keys ['nmae']; expected some of ['bounds', 'inner', 'name']"),
    ([1, 2], "[outer] must be a table/dict, got list"),
    ({"bounds": "wide"}, "[outer]: bounds: expected a list of numbers, got 'wide'"),
    ({"inner": {"gain": 9}}, "[outer.inner]: gain must be in (0, 5], got 9"),
    ({"inner": {"gian": 1}}, "unknown [outer.inner] keys ['gian']"),
    ({"inner": {"gain": float("nan")}}, "gain must be in (0, 5], got nan"),
])
def test_bad_tables_name_the_key_and_the_file(data, words):
    with pytest.raises(ConfigError) as info:
        build(data, source="lab.toml")
    assert words in str(info.value) and str(info.value).startswith("lab.toml: ")


def test_toml_errors_name_the_file(tmp_path):
    p = tmp_path / "a.toml"
    p.write_text("[x]\ny = 1\n")
    assert read_toml(p) == {"x": {"y": 1}}
    p.write_text("[x\n")
    with pytest.raises(ConfigError, match=f"{p} is not valid TOML"):
        read_toml(p)
    with pytest.raises(KeyError, match="cannot read config file .*missing.toml"):
        read_toml(tmp_path / "missing.toml", KeyError)


def test_check_keys_returns_a_copy():
    d = {"a": 1}
    out = check_keys(d, ("a", "b"), "t")
    assert out == d and out is not d


@pytest.mark.parametrize("x, ok", [(0.5, True), (1, True), (np.float64(0.2), True), (0.0, False), (2.0, True),
                                   (2.0000001, False), (math.nan, False), (math.inf, False), (True, False),
                                   ("1", False), (None, False)])
def test_in_range_refuses_nan_inf_bool_and_text(x, ok):
    assert in_range(x, 0.0, 2.0, lo_open=True) is ok


def test_integer_ranges():
    assert in_range(np.int64(3), 1, 200, integer=True) and not in_range(3.0, 1, 200, integer=True)
    assert in_range(10**400, 0, integer=True) and not in_range(10**400, 0, 10**6, integer=True)
    with pytest.raises(ValueError, match=r"^n_robots must be an integer in \[1, 200\], got -3$"):
        require_in_range(-3, "n_robots", 1, 200, integer=True)
    with pytest.raises(ValueError, match=r"^dt must be >= 0 s, got nan$"):
        require_in_range(math.nan, "dt", 0.0, unit="s")
