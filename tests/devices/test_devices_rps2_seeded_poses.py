"""rps's random poses follow numpy's global generator, as under rps: a script that calls ``np.random.seed`` draws the
same goals on every run (they were drawn from fresh entropy, so the same seeded script reached its goals on one run
and stopped short on the next)."""
import numpy as np

from swarmdeck.devices.rps import rps_aliases


def test_generate_initial_conditions_and_random_poses_repeat_under_np_random_seed():
    with rps_aliases():
        from rps.utilities.misc import generate_initial_conditions, generate_random_poses, generate_random_positions

        draws = []
        for _ in range(2):
            np.random.seed(7)
            draws.append((generate_initial_conditions(5, spacing=0.3), generate_random_poses(4, spacing=0.4),
                          generate_random_positions(3)))
    for first, second in zip(*draws):
        assert np.array_equal(first, second)
    ic, poses, positions = draws[0]
    assert ic.shape == (3, 5) and poses.shape == (3, 4) and positions.shape == (2, 3)
    gaps = np.linalg.norm(ic[:2, :, None] - ic[:2, None, :], axis=0) + np.eye(5)
    assert gaps.min() >= 0.3  # rps's spacing still holds
    with rps_aliases():
        from rps.utilities.misc import generate_initial_conditions

        np.random.seed(8)
        other = generate_initial_conditions(5, spacing=0.3)
    assert not np.array_equal(other, ic)  # another seed, other poses
