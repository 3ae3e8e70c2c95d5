"""Broker passwords never appear in messages or reprs."""
import pytest

from swarmdeck.console.cli import main
from swarmdeck.devices.net.mqtt_config import parse_broker_url, redact_url


def test_repr_hides_the_password():
    cfg = parse_broker_url("mqtt://alice:s3cret@127.0.0.1:1883/lab/")
    assert cfg.password == "s3cret" and cfg.username == "alice"
    assert "s3cret" not in repr(cfg) and "s3cret" not in cfg.url


@pytest.mark.parametrize("url", ["mqtt://alice:s3cret@127.0.0.1:99999/", "http://alice:s3cret@host/", "mqtt://alice:s3cret@:1883"])
def test_bad_url_messages_hide_the_password(url, capsys):
    with pytest.raises(ValueError) as err:
        parse_broker_url(url)
    assert "s3cret" not in str(err.value) and "alice:***@" in str(err.value)
    assert main(["robots", "--broker", url]) == 2
    assert "s3cret" not in capsys.readouterr().err


@pytest.mark.parametrize("url, shown", [("mqtt://h:1", "mqtt://h:1"), ("mqtt://u@h:1", "mqtt://u@h:1"),
                                        ("mqtts://u:p@h:1/x/", "mqtts://u:***@h:1/x/"), ("nonsense", "nonsense")])
def test_redact_url(url, shown):
    assert redact_url(url) == shown


def test_no_robots_message_hides_the_password():
    from swarmdeck.devices.net.console_robots import NetworkRobots

    with pytest.raises(ValueError) as err:
        NetworkRobots.connect("mqtt://alice:s3cret@127.0.0.1:1", n_robots=1, wait_for_poses=0.2)
    assert "s3cret" not in str(err.value) and "alice:***@" in str(err.value)
