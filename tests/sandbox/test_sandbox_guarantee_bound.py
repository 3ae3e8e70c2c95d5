"""The stated guarantee (REFERENCE.md §17): Clopper–Pearson upper bounds and run counts against known values,
the rule of three, the statement's wording, and bad input named."""
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.stats import binom

from swarmdeck.console.sandbox.guarantee import Guarantee, percent, runs_needed, upper_bound


@pytest.mark.parametrize("runs,failures,confidence,expected", [
    (10, 0, 0.95, 0.2589),   # 1 − 0.05^(1/10)
    (20, 0, 0.95, 0.1391),
    (10, 1, 0.95, 0.3942),   # one-sided 95 % Clopper–Pearson table values
    (10, 5, 0.95, 0.7776),
    (10, 1, 0.975, 0.4450),  # = the upper end of the two-sided 95 % interval for 1/10
    (299, 0, 0.95, 0.009969),
])
def test_the_bound_matches_clopper_pearson_table_values(runs, failures, confidence, expected):
    assert upper_bound(runs, failures, confidence) == pytest.approx(expected, abs=1e-4 if expected > 0.05 else 1e-6)


@pytest.mark.parametrize("runs", [100, 299, 1000, 10_000])
def test_no_failure_is_the_rule_of_three(runs):
    bound = upper_bound(runs, 0, 0.95)
    assert bound == pytest.approx(1 - 0.05 ** (1 / runs), rel=1e-12)
    assert bound < 3 / runs and bound == pytest.approx(3 / runs, rel=0.02)


def test_every_run_failed_bounds_nothing():
    assert upper_bound(7, 7, 0.95) == 1.0


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 2000), st.data(), st.sampled_from([0.8, 0.9, 0.95, 0.99]))
def test_the_bound_solves_its_defining_equation(runs, data, confidence):
    failures = data.draw(st.integers(0, runs - 1))
    p = upper_bound(runs, failures, confidence)
    assert 0.0 < p < 1.0
    assert binom.cdf(failures, runs, p) == pytest.approx(1 - confidence, abs=1e-6)  # P(Bin(n, p) ≤ x) = δ


@pytest.mark.parametrize("epsilon,confidence,failures,expected", [
    (0.01, 0.95, 0, 299),    # REFERENCE §17
    (0.05, 0.95, 0, 59),     # the 95/95 success-run table: 59, 93, 124
    (0.05, 0.95, 1, 93),
    (0.05, 0.95, 2, 124),
    (0.01, 0.99, 0, 459),
])
def test_runs_needed_matches_known_values(epsilon, confidence, failures, expected):
    n = runs_needed(epsilon, confidence, failures)
    assert n == expected
    assert upper_bound(n, failures, confidence) <= epsilon < upper_bound(n - 1, failures, confidence)


@settings(max_examples=40, deadline=None)
@given(st.floats(0.001, 0.5), st.floats(0.5, 0.999))
def test_runs_needed_is_the_smallest_n_with_no_failure(epsilon, confidence):
    n = runs_needed(epsilon, confidence)
    assert (1 - epsilon) ** n <= (1 - confidence) * (1 + 1e-9)
    assert n == 1 or (1 - epsilon) ** (n - 1) > (1 - confidence) * (1 - 1e-9)


def test_the_statement_reads_as_the_issue_asks():
    g = Guarantee(299, 0, 0.95, 0.01)
    assert g.statement() == "P(contact per run) ≤ 1.0 % at 95 % confidence (299 runs, 0 contacts)"
    assert g.met is True and g.shortfall() is None and g.method.startswith("rule of three")
    d = g.to_dict()
    assert d["runs_needed"] == 299 and d["bound"] == pytest.approx(0.009969, abs=1e-6)


def test_a_bound_above_epsilon_says_so_and_how_many_runs_would_reach_it():
    g = Guarantee(8, 0, 0.95, 0.01)
    assert g.met is False
    assert g.shortfall() == ("P(contact per run) ≤ 31.3 % at 95 % confidence (8 runs, 0 contacts): above the "
                             "required 1.0 %; 299 runs with 0 contacts would reach it")
    one = Guarantee(100, 1, 0.95, 0.05)
    assert one.method == "Clopper-Pearson" and "1 contact)" in one.statement()
    assert "93 runs with 1 contacts would reach it" not in (one.shortfall() or "")  # 100 ≥ 93: met
    assert one.met is True


def test_percentages_round_up_never_down():
    assert percent(0.009969) == "1.0 %"
    assert percent(0.0101) == "1.1 %"
    assert percent(0.000299) == "0.030 %"
    assert percent(1.0) == "100.0 %"
    p = upper_bound(30_000, 0, 0.95)
    assert float(percent(p).split()[0]) / 100 >= p


@pytest.mark.parametrize("call,message", [
    (lambda: upper_bound(10, 0, 1.0), "confidence must be a number strictly between 0 and 1"),
    (lambda: upper_bound(10, 0, 0.0), "confidence must be"),
    (lambda: upper_bound(10, 0, math.nan), "confidence must be"),
    (lambda: upper_bound(10, 0, 95), "got 95"),
    (lambda: upper_bound(3, 4), "more failures (4) than runs (3)"),
    (lambda: upper_bound(0, 0), "runs must be a positive integer"),
    (lambda: upper_bound(10, -1), "failures must be a non-negative integer"),
    (lambda: upper_bound(10, True), "failures must be"),
    (lambda: runs_needed(0.0), "epsilon (the target P(contact per run)) must be a number strictly between 0 and 1"),
    (lambda: runs_needed(-0.01), "epsilon"),
    (lambda: runs_needed(1.0), "epsilon"),
    (lambda: runs_needed(0.01, 1.5), "confidence must be"),
    (lambda: runs_needed(1e-9, 0.95), "runs, more than 10000000"),
    (lambda: Guarantee(5, 6), "more failures (6) than runs (5)"),
    (lambda: Guarantee(5, 0, 0.95, 0.0), "epsilon"),
])
def test_bad_input_is_refused_naming_what_is_wrong(call, message):
    with pytest.raises(ValueError) as info:
        call()
    assert message in str(info.value)
