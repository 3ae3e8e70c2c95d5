"""The sweep's design, pure: VALUES parsing, declared parameters read from the source, the refusals (undeclared
parameter named with the declared ones, empty range, too many grid points with the count and a hint)."""
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.console.sandbox.bundle import ScriptBundle
from swarmdeck.console.sweep.campaign import SweepSpec, plan
from swarmdeck.console.sweep.design import (
    MAX_POINTS,
    DesignError,
    check_axes,
    check_size,
    grid_points,
    parse_axis,
    parse_counts,
    random_points,
)
from swarmdeck.devices.experiment_params import ParamError, declared_in_source

SCRIPT = b"""
from swarmdeck.devices import params
p = params(gain=1.0, robots=20, mode="ring", fast=False)
def experiment(arena):
    pass
"""


def bundle(source: bytes = SCRIPT) -> ScriptBundle:
    return ScriptBundle.single("ctl.py", source)


def test_the_three_forms_of_values():
    assert parse_axis("gain=0.5:2:4").values == (0.5, 1.0, 1.5, 2.0)
    assert parse_axis("gain=0.5,1,2").values == (0.5, 1, 2)
    log = parse_axis("gain=log:0.1:10:5")
    assert log.kind == "log" and log.values == (0.1, pytest.approx(0.316227766017), 1.0, pytest.approx(3.16227766017), 10.0)
    assert parse_axis("mode=ring,line").values == ("ring", "line")
    assert parse_axis("gain=3").values == (3,)


@pytest.mark.parametrize("spec, words", [
    ("gain=", "empty range"), ("gain=0.5:2:0", "empty range"), ("gain=1:2:-3", "empty range"),
    ("gain=1:2:x", "whole number"), ("gain", "NAME=VALUES"), ("=1,2", "NAME=VALUES"), ("gain=1,,2", "empty value"),
    ("gain=log:0:1:3", "> 0"), ("gain=log:1:3", "log:FIRST:LAST:COUNT"), ("gain=1:nan:3", "finite"),
    ("2x=1,2", "not a parameter name"),
])
def test_bad_values_are_named(spec, words):
    with pytest.raises(DesignError, match=words):
        parse_axis(spec)


@settings(max_examples=40)
@given(st.floats(-100, 100), st.floats(-100, 100), st.integers(1, 50))
def test_a_range_has_its_count_and_its_ends(lo, hi, n):
    axis = parse_axis(f"gain={lo!r}:{hi!r}:{n}")
    assert len(axis.values) <= n  # equal values (lo == hi) run once
    assert math.isclose(axis.values[0], lo, rel_tol=1e-9, abs_tol=1e-9)
    if abs(lo - hi) > 1e-6 and n > 1:
        assert len(axis.values) == n and math.isclose(axis.values[-1], hi, rel_tol=1e-9, abs_tol=1e-9)


def test_declared_parameters_are_read_without_running_the_script():
    assert declared_in_source(SCRIPT.decode()) == {"gain": 1.0, "robots": 20, "mode": "ring", "fast": False}
    assert declared_in_source("import swarmdeck.devices as d\nq = d.params(k=2)\n") == {"k": 2}
    assert declared_in_source("print('no parameters')\n") is None
    with pytest.raises(ParamError, match="must be a literal"):
        declared_in_source("from swarmdeck.devices import params\nimport os\np = params(k=os.getpid())\n")


def test_an_undeclared_parameter_is_named_with_the_declared_ones():
    with pytest.raises(DesignError) as exc:
        plan(SweepSpec(bundle(), (parse_axis("gian=1,2"),)))
    text = str(exc.value)
    assert "'gian'" in text and "ctl.py" in text and "gain=1.0" in text and "mode='ring'" in text


def test_values_take_the_declared_types():
    axes = check_axes([parse_axis("robots=10:30:3"), parse_axis("fast=true,false")],
                      {"robots": 20, "fast": False}, "ctl.py")
    assert axes[0].values == (10, 20, 30) and all(type(v) is int for v in axes[0].values)
    with pytest.raises(DesignError, match="robots is a int"):
        check_axes([parse_axis("robots=1.5,2")], {"robots": 20}, "ctl.py")
    with pytest.raises(DesignError, match="given twice"):
        check_axes([parse_axis("gain=1"), parse_axis("gain=2")], {"gain": 1.0}, "ctl.py")


def test_a_million_grid_points_are_refused_with_the_count_and_a_hint():
    axes = tuple(parse_axis(f"{n}=0:1:100") for n in ("a", "b", "c"))
    with pytest.raises(DesignError) as exc:
        check_size(axes, "grid", None, 1, 30)
    assert "1,000,000 grid points" in str(exc.value) and "--design random --samples" in str(exc.value)
    with pytest.raises(DesignError, match="200,000 grid points"):  # robot counts are points of the grid too
        check_size(axes[:2], "grid", None, 20, 1)
    assert check_size(axes[:2], "grid", None, 2, 3) == 100 * 100 * 2 * 3
    source = b"from swarmdeck.devices import params\np = params(a=0.0, b=0.0, c=0.0)\n"
    with pytest.raises(DesignError, match=f"more than the {MAX_POINTS:,}"):  # refused before any point is built
        plan(SweepSpec(bundle(source), axes))


def test_grid_and_random_designs():
    axes = check_axes([parse_axis("gain=1,2"), parse_axis("robots=10,20,30")], {"gain": 1.0, "robots": 20}, "x")
    assert grid_points(axes) == [{"gain": g, "robots": r} for g in (1.0, 2.0) for r in (10, 20, 30)]
    lin = check_axes([parse_axis("gain=log:0.1:10:3"), parse_axis("robots=10:50:2")], {"gain": 1.0, "robots": 20}, "x")
    drawn = random_points(lin, {"gain": 1.0, "robots": 20}, 50, seed=4)
    assert drawn == random_points(lin, {"gain": 1.0, "robots": 20}, 50, seed=4)
    assert all(0.1 <= d["gain"] <= 10 and 10 <= d["robots"] <= 50 and type(d["robots"]) is int for d in drawn)
    assert parse_counts("10,20", "robots") == (10, 20) and parse_counts(None, "robots") == (None,)
    with pytest.raises(DesignError, match="positive whole number"):
        parse_counts("0,5", "robots")


def test_the_plan_runs_each_point_with_each_count_and_seed_under_distinct_keys():
    the_plan = plan(SweepSpec(bundle(), (parse_axis("gain=1,2"),), seeds=3, robots=(4, 6)))
    assert len(the_plan.runs) == 2 * 2 * 3 and len({r.key for r in the_plan.runs}) == 12
    first = the_plan.runs[0]
    assert dict(first.params) == {"gain": 1.0, "robots": 4} and first.task.config.n_robots == 4
    assert plan(SweepSpec(bundle(), (parse_axis("gain=1,2"),), seeds=3, robots=(4, 6))).runs[5].key == the_plan.runs[5].key
    other = plan(SweepSpec(bundle(SCRIPT + b"# changed\n"), (parse_axis("gain=1,2"),), seeds=3, robots=(4, 6)))
    assert other.runs[0].key != first.key  # a changed script runs anew
