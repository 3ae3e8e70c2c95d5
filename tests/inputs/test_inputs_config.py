"""InputConfig / ListenerConfig from dicts and TOML."""
from __future__ import annotations

import pytest

from swarmdeck.inputs import ConfigError, InputConfig, InputHub, ListenerConfig, TcpListener, UdpListener

TOML = """
[inputs]
bounds = [-2.0, 2.0, -1.0, 1.0]

[[inputs.listeners]]
port = 3333
host = "0.0.0.0"
timeout = 0.75
calibration = { flip_y = true }
source_calibrations = { "*TuioPad@*" = { flip_x = true } }

[[inputs.listeners]]
preset = "manososc"

[[inputs.listeners]]
transport = "tcp"
port = 3334
streams = [{ name = "pad", address = "/pad/{id}", id_fields = ["id"], x_arg = 0, y_arg = 1 }]

[inputs.density]
sigma = 0.25
fade = 0.3
"""


def test_toml_section_builds_every_listener(tmp_path):
    path = tmp_path / "swarmdeck.toml"
    path.write_text(TOML)
    cfg = InputConfig.load_toml(path)
    a, b, c = cfg.listeners
    assert (a.host, a.port, a.timeout, a.calibration.flip_y) == ("0.0.0.0", 3333, 0.75, True)
    assert a.calibration.bounds == (-2.0, 2.0, -1.0, 1.0)
    assert a.source_calibrations[0][0] == "*TuioPad@*" and a.source_calibrations[0][1].flip_x
    assert (b.name, b.port, b.tuio, b.streams[0].name) == ("manososc", 7110, False, "manososc")
    assert (c.transport, c.port, c.streams[0].match("/pad/7")) == ("tcp", 3334, {"id": "7"})
    assert (cfg.density.sigma, cfg.density.fade) == (0.25, 0.3)
    hub = InputHub.from_config(cfg)
    assert [type(s) for s in hub.sources] == [UdpListener, UdpListener, TcpListener]


def test_defaults_without_an_inputs_table(tmp_path):
    path = tmp_path / "empty.toml"
    path.write_text("[other]\nx = 1\n")
    cfg = InputConfig.load_toml(path)
    (lc,) = cfg.listeners
    assert (lc.transport, lc.host, lc.port, lc.tuio, lc.timeout) == ("udp", "127.0.0.1", 3333, True, 1.0)


@pytest.mark.parametrize("d, words", [
    ({"listeners": [{"prot": 1}]}, "unknown listener keys ['prot']"),
    ({"listeners": [{"port": 70000}]}, "port must be an int in 0..65535"),
    ({"listeners": [{"transport": "ws"}]}, "transport must be 'udp' or 'tcp'"),
    ({"listeners": [{"timeout": -1}]}, "timeout must be a positive"),
    ({"listeners": [{"preset": "kinect"}]}, "unknown preset 'kinect'"),
    ({"listeners": [{"calibration": {"scale": "big"}}]}, "calibration scale"),
    ({"listeners": {"port": 1}}, "array of tables"),
    ({"bounds": [1, 0, 0, 1]}, "min < max"),
    ({"density": {"sigma": -1}}, "density sigma must be a positive"),
    ({"extra": 1}, "unknown [inputs] keys"),
])
def test_bad_values_are_named(d, words):
    with pytest.raises(ConfigError) as exc:
        InputConfig.from_dict(d)
    assert words in str(exc.value)


def test_bad_toml_file(tmp_path):
    p = tmp_path / "bad.toml"
    p.write_text("[inputs\n")
    with pytest.raises(ConfigError, match="not valid TOML"):
        InputConfig.load_toml(p)
    with pytest.raises(ConfigError, match="cannot read"):
        InputConfig.load_toml(tmp_path / "missing.toml")


def test_preset_overrides():
    lc = ListenerConfig.from_preset("leap-osc", port=9000)
    assert (lc.port, lc.tuio) == (9000, False)
