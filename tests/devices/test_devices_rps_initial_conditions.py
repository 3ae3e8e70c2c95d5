"""The rps facade speaks rps's (3, N) shape in its initial-conditions errors."""
import numpy as np
import pytest

from swarmdeck.devices.rps.robotarium import Robotarium


def test_integer_initial_conditions_are_described_as_3_by_n():
    with pytest.raises(ValueError) as exc:
        Robotarium(2, initial_conditions=np.array([[0, 1], [0, 0], [0, 0]]), sim_in_real_time=False)
    text = str(exc.value)
    assert "(3, N)" in text and "(N, 3)" not in text and "float" in text and "int" in text
