"""check_command never raises: text, complex, ragged or missing commands stop the robots and are described."""
import numpy as np
import pytest

from swarmdeck.devices.net.transport import check_command


@pytest.mark.parametrize("v", [["a", "b"], [1 + 2j, 0.0], None, [[0.0, 1.0], [1.0]], "fast", [0.1]])
def test_bad_speeds_stop_every_robot(v):
    cmd = check_command([0, 1], v, [0.0, 0.0])
    assert cmd.ids.tolist() == [0, 1] and cmd.v.tolist() == [0.0, 0.0] and cmd.w.tolist() == [0.0, 0.0]
    assert cmd.zeroed.all() and "v and w must be real numbers" in cmd.problems[0]


@pytest.mark.parametrize("leds", ["red", [["a", "b", "c"]] * 2, [[1, 2, 3], [4, 5, np.nan]], [[1, 2], [3]]])
def test_bad_leds_are_dropped_speeds_kept(leds):
    cmd = check_command([0, 1], [0.1, 0.2], [0.0, 0.5], leds)
    assert cmd.leds is None and cmd.v.tolist() == [0.1, 0.2] and "leds must be" in cmd.problems[0]


def test_good_leds_both_forms():
    one = check_command([0, 1], [0.1, 0.2], [0.0, 0.0], [[255, 0, 0], [0, 300, -4]])
    assert one.leds.shape == (2, 2, 3) and one.leds[1, 0].tolist() == [0, 255, 0]
