"""The falsifier's search (issue 31 item 3): candidates stay inside the set-up tolerance and the tracking noise, the
cross-entropy method is deterministic given its seed and keeps to its budget, and on the near-miss fixture
(examples/near_miss.py: two robots pass 75 mm clear unless the set-up errors line up in one corner of the tolerance)
it finds the contact that uniform sampling with the same budget misses. The runs are the verification plant in this
process (tests/falsify_fixtures.py); tests/sandbox/test_sandbox_verify_falsify.py runs the same search jailed."""
from pathlib import Path

import numpy as np
import pytest
from falsify_fixtures import NEAR_MISS_SPACE, near_miss_objective, near_miss_run
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from swarmdeck.console.sandbox.falsification import SearchCancelled, falsify_script
from swarmdeck.console.sandbox.falsify import OFFSET_SIGMAS, SearchSpace, cross_entropy, uniform_search
from swarmdeck.console.sandbox.plant import Disturbances
from swarmdeck.console.sandbox.verification import VerificationConfig, load_script
from swarmdeck.devices.fleet.setup import ACCEPT_HEADING, ACCEPT_POSITION

BUDGET = 40


@settings(max_examples=60)
@given(arrays(np.float64, 18, elements=st.floats(-5.0, 5.0)))
def test_every_candidate_decodes_inside_the_tolerance_and_the_noise(z):
    probe = SearchSpace.within_noise(3, 0.002, 0.01).decode(z)
    setup, offset = np.array(probe.setup), np.array(probe.offset)
    assert setup.shape == offset.shape == (3, 3)
    assert np.all(np.hypot(setup[:, 0], setup[:, 1]) <= ACCEPT_POSITION + 1e-12)
    assert np.all(np.abs(setup[:, 2]) <= ACCEPT_HEADING + 1e-12)
    assert np.all(np.abs(offset[:, :2]) <= OFFSET_SIGMAS * 0.002 + 1e-12)
    assert np.all(np.abs(offset[:, 2]) <= OFFSET_SIGMAS * 0.01 + 1e-12)


def bowl(batch):
    return np.linalg.norm(batch - 0.5, axis=1)


def test_the_search_is_deterministic_given_its_seed_and_keeps_to_its_budget():
    a, b = cross_entropy(bowl, 4, 37, seed=7, stop_at=-1.0), cross_entropy(bowl, 4, 37, seed=7, stop_at=-1.0)
    assert np.array_equal(a.candidates, b.candidates) and np.array_equal(a.values, b.values)
    assert len(a.values) == 37 and a.generations == 4  # the last generation cut to what was left
    assert not np.array_equal(cross_entropy(bowl, 4, 37, seed=8, stop_at=-1.0).candidates, a.candidates)
    assert np.all(np.abs(a.candidates) <= 1.0)
    assert a.values[-10:].min() < a.values[:10].min()  # it moved towards the minimum


def test_the_search_stops_at_a_contact():
    found = cross_entropy(lambda batch: np.where(batch[:, 0] > 0.0, 0.0, 1.0), 2, 100, seed=0)
    assert found.values.min() == 0.0 and len(found.values) == 10  # the first generation had one: nothing is closer


def test_bad_budgets_and_objectives_are_refused_naming_them():
    with pytest.raises(ValueError, match="falsification budget must be a positive integer number of runs, got 0"):
        cross_entropy(bowl, 2, 0, seed=0)
    with pytest.raises(ValueError, match="the objective gave 1 values for 10 candidates"):
        cross_entropy(lambda batch: np.zeros(1), 2, 10, seed=0)
    with pytest.raises(ValueError, match="falsify_budget must be a non-negative integer number of runs, got -1"):
        VerificationConfig(falsify_budget=-1)
    with pytest.raises(ValueError, match="n_robots must be a positive integer"):
        SearchSpace(0)


def test_a_run_that_measured_nothing_is_never_the_worst_case():
    found = uniform_search(lambda batch: np.full(len(batch), np.nan), 2, 5, seed=0)
    assert np.all(np.isinf(found.values))


def test_the_fixture_passes_75_mm_clear_from_its_nominal_start():
    assert NEAR_MISS_SPACE == SearchSpace.within_noise(2, Disturbances().pose_noise_xy, Disturbances().pose_noise_theta)
    assert near_miss_run(np.zeros(12)) == pytest.approx(0.075, abs=0.002)


def test_the_falsifier_finds_the_contact_that_uniform_sampling_misses_with_the_same_budget():
    found = {seed: cross_entropy(near_miss_objective, NEAR_MISS_SPACE.dim, BUDGET, seed).first_at_most(0.0)
             for seed in (3, 4)}
    assert found == {3: 13, 4: 4}  # runs until the first contact, deterministic given the seed
    uniform = uniform_search(near_miss_objective, NEAR_MISS_SPACE.dim, BUDGET, 3)
    assert uniform.first_at_most(0.0) is None and len(uniform.values) == BUDGET
    assert uniform.values.min() > 0.005  # not even close: 5 mm or more to spare in every one of the 40 runs


NEAR_MISS_CONFIG = VerificationConfig(n_robots=2, duration=2.2, runs=1, seed=4, paced_runs=0, falsify_budget=20)


def test_a_cancelled_searched_run_stops_the_search():
    bundle = load_script(Path(__file__).parents[2] / "examples" / "near_miss.py")
    with pytest.raises(SearchCancelled, match="a searched run was cancelled"):
        falsify_script(bundle, NEAR_MISS_CONFIG, 2, lambda tasks: [None] * len(tasks))


def test_searched_runs_that_measured_nothing_are_reported_not_ranked():
    bundle = load_script(Path(__file__).parents[2] / "examples" / "near_miss.py")
    crashed = {"ended_by": "error", "error": "boom", "contacts": None}  # what run_task gives when no Arena was built
    entry = falsify_script(bundle, NEAR_MISS_CONFIG, 2, lambda tasks: [dict(crashed) for _ in tasks])
    assert entry["worst_case"] is None and entry["runs"] == 20 and not entry["found_contact"]
    assert entry["statement"] == ("falsification skipped: no searched run measured a clearance (see the raw runs' "
                                  "errors)")
