"""The arena's step does its bookkeeping without repeating work (issue 28: the rps examples' run time):
``Certified.changed`` is ``np.isclose``'s very test without its argument handling (the same mask for every float,
infinities, NaN and signed zeros included), and the robot ports' optional capabilities (a sink behind a trust
boundary, a sink that reports fixed obstacles) are read once when the Arena's robots are built, not at every step."""
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from swarmdeck.core.ports import SensedPoses
from swarmdeck.core.robot_models import robot_params
from swarmdeck.devices.pipeline import Certified
from swarmdeck.devices.stepped import SteppedRobots

SPECIAL = [0.0, -0.0, 1e-12, -1e-12, 1e-9, 5e-324, 1e308, np.inf, -np.inf, np.nan, 1.0, 1.0 + 1e-9, 1.0 + 2e-9]
floats = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.sampled_from(SPECIAL))


def _cert(v, w, v0, w0):
    n = len(v)
    return Certified(v, w, np.zeros((n, 2)), v0, w0, np.zeros(n, bool), np.zeros(n, bool), True, "ok", None)


@settings(max_examples=200, deadline=None)
@given(st.integers(1, 8).flatmap(lambda n: st.tuples(*[arrays(np.float64, n, elements=floats)] * 4)))
def test_changed_is_isclose_of_v_and_w(arrs):
    v, w, v0, w0 = arrs
    w0 = np.where(np.arange(len(w0)) % 2 == 0, w, w0)  # some robots unchanged in ω, bit for bit
    with np.errstate(invalid="ignore"):
        want = ~(np.isclose(v, v0, rtol=1e-9, atol=1e-12) & np.isclose(w, w0, rtol=1e-9, atol=1e-12))
    got = _cert(v, w, v0, w0).changed()
    assert got.dtype == want.dtype and got.shape == want.shape and np.array_equal(got, want)


def test_changed_takes_other_arrays_as_isclose_does():
    v = np.array([1, 2, 3], dtype=np.int64)
    v0 = np.array([1.0, 2.0 + 1e-6, 3.0], dtype=np.float32)
    w = w0 = np.zeros(3)
    want = ~(np.isclose(v, v0, rtol=1e-9, atol=1e-12) & np.isclose(w, w0, rtol=1e-9, atol=1e-12))
    assert np.array_equal(_cert(v, w, v0, w0).changed(), want)


class _CountingRobots:
    """Two robots standing still that count every look-up of the optional capabilities' names."""

    name = "counting"

    def __init__(self, obstacles):
        self.lookups = 0
        self._obstacles = obstacles
        self._time = 0.0

    def __getattr__(self, name):  # only names the class does not have: send_nominal, obstacles (when absent)
        if name in ("send_nominal", "obstacles"):
            self.lookups += 1
        raise AttributeError(name)

    def read(self, now):
        return SensedPoses(np.arange(2), np.array([[0.0, 0.0, 0.0], [0.5, 0.0, 0.0]]), np.ones(2, bool), time=self._time)

    def send(self, ids, v, w):
        self._time += 0.033

    def hold(self):
        pass

    def health(self):
        return "ok"

    def close(self):
        pass


class _CountingRobotsWithObstacles(_CountingRobots):
    def obstacles(self):
        self.lookups += 1
        return self._obstacles


def test_the_ports_capabilities_are_read_once_when_the_robots_are_built():
    plain = _CountingRobots(None)
    robots = SteppedRobots(plain, params=robot_params("gritsbot"), dt=0.033)
    built = plain.lookups
    for _ in range(5):
        assert robots.nominal_sink is None and robots.obstacles() is None
        robots.step(np.zeros(2), np.zeros(2))
    assert plain.lookups == built  # not looked up again at every step

    walls = _CountingRobotsWithObstacles(np.array([[1.0, 1.0], [1.2, 1.0]]))
    robots = SteppedRobots(walls, params=robot_params("gritsbot"), dt=0.033)
    built = walls.lookups
    for _ in range(3):
        assert robots.obstacles().tolist() == [[1.0, 1.0], [1.2, 1.0]]  # the sink's obstacles, read every step
    assert walls.lookups == built + 3


@settings(max_examples=100, deadline=None)
@given(st.integers(0, 12).flatmap(lambda n: arrays(np.float64, (n, 3), elements=st.floats(-0.3, 0.3))))
def test_colliding_pairs_without_a_pair_is_the_same_empty_answer(poses):
    from swarmdeck.devices.validation import ValidationRules, colliding_pairs

    rules = ValidationRules()
    got = colliding_pairs(poses, rules)
    x = poses[:, 0] + rules.collision_shift * np.cos(poses[:, 2])
    y = poses[:, 1] + rules.collision_shift * np.sin(poses[:, 2])
    want = [(i, j) for i in range(len(poses)) for j in range(i + 1, len(poses))
            if np.hypot(x[i] - x[j], y[i] - y[j]) <= rules.collision_distance]
    assert got.dtype == np.intp and got.shape == (len(want), 2) and got.tolist() == [list(p) for p in want]
