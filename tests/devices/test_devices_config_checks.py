"""Configuration dataclasses of devices reject NaN, inf, bools and non-positive values, naming the field."""
import numpy as np
import pytest

from swarmdeck.devices import GritsBotParams
from swarmdeck.devices.battery import BatteryParams
from swarmdeck.devices.net.firmware import FirmwareParams
from swarmdeck.devices.net.streamer import StreamerConfig


@pytest.mark.parametrize("cls, field", [
    (GritsBotParams, "wheel_radius"), (GritsBotParams, "lookahead"), (StreamerConfig, "pose_timeout"),
    (FirmwareParams, "command_timeout"), (BatteryParams, "capacity_ah"),
])
@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan"), float("inf"), True, "0.5"])
def test_rejected_with_the_field_named(cls, field, bad):
    with pytest.raises(ValueError, match=rf"{cls.__name__}\.{field} must be"):
        cls(**{field: bad})


@pytest.mark.parametrize("value", [0.25, 1, np.float32(0.5), np.int64(2)])
def test_numbers_of_any_numeric_type_accepted(value):
    assert BatteryParams(capacity_ah=value).capacity_ah == value
    assert StreamerConfig(period=value).period == value


def test_battery_currents_may_be_zero_but_not_infinite():
    BatteryParams(idle_current=0.0, motor_current_per_wheel_speed=0.0)
    with pytest.raises(ValueError, match="BatteryParams.idle_current"):
        BatteryParams(idle_current=float("inf"))
