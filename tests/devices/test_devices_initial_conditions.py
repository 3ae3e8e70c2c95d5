"""Random initial conditions: every N up to the maximum, separated, inside; a clear error above."""
import numpy as np
import pytest
from scipy.spatial.distance import pdist

from swarmdeck.devices import max_robots, random_initial_poses


def test_every_n_up_to_the_maximum_fits():
    top = max_robots()
    assert top >= 100
    for n in list(range(1, 21)) + [top // 2, top]:
        p = random_initial_poses(n, rng=n)
        assert p.shape == (n, 3)
        if n > 1:
            assert pdist(p[:, :2]).min() >= 0.23 - 1e-12
        assert np.all(np.abs(p[:, 0]) <= 1.6 - 0.13 + 1e-12) and np.all(np.abs(p[:, 1]) <= 1.0 - 0.13 + 1e-12)


def test_too_many_names_the_maximum():
    top = max_robots()
    with pytest.raises(ValueError, match=rf"at most {top}"):
        random_initial_poses(top + 1)


def test_larger_arena_holds_more():
    assert max_robots((-8.0, 8.0, -5.0, 5.0)) >= 1000
    p = random_initial_poses(1000, (-8.0, 8.0, -5.0, 5.0), rng=0)
    assert pdist(p[:, :2]).min() >= 0.23 - 1e-12


@pytest.mark.parametrize("bad", [0, -3, 2.5, True, "4"])
def test_bad_counts(bad):
    with pytest.raises(ValueError, match="number of robots"):
        random_initial_poses(bad)
