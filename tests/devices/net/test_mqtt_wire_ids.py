"""Robot ids on the wire are plain ASCII digits: other Unicode digits are bad input, never an exception."""
import json

import pytest

from swarmdeck.devices.net.mqtt_config import parse_broker_url
from swarmdeck.devices.net.wire import decode_poses


@pytest.mark.parametrize("key", ["²", "³", "١", "٣", "１", "-1", "1.0", " 1", "9999999999"])
def test_pose_keys_that_are_not_ascii_ids_are_problems(key):
    msg = decode_poses(json.dumps({key: {"x": 0.0, "y": 0.0, "theta": 0.0}, "2": {"x": 1.0, "y": 0.0, "theta": 0.0}}).encode())
    assert msg.ids.tolist() == [2] and len(msg.problems) == 1


@pytest.mark.parametrize("rid", ["٣", "²", "１"])
def test_topics_with_unicode_digits_name_no_robot(rid):
    cfg = parse_broker_url("mqtt://127.0.0.1:1883")
    assert cfg.robot_id_of_status_topic(f"{rid}/status") is None
    assert cfg.robot_id_of_status_topic("3/status") == 3
