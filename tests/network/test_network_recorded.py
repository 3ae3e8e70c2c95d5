"""A decentralised run's communication graph and traffic are recorded (`swarmdeck run --record`: the Frame's
``network`` on /swarmdeck/frame and Foxglove's /foxglove/network) and played back; Frames without a network
are written exactly as before (no ``network`` key), so old recordings read unchanged."""
from __future__ import annotations

import json

import numpy as np
from mcap.reader import make_reader

from swarmdeck.console.cli import main
from swarmdeck.console.recording.codec import decode_frame, encode_frame
from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.console.runtime.network_frame import NetworkFrame
from swarmdeck.examples import decentralised_rendezvous


def _frame(tick: int, network: NetworkFrame | None) -> Frame:
    n = 3
    return Frame(tick=tick, time=0.033 * tick, poses=np.zeros((n, 3)) + tick * 0.01, ids=np.arange(n),
                 nominal=np.zeros((n, 2)), safe=np.zeros((n, 2)), v=np.zeros(n), w=np.zeros(n), network=network)


def test_the_network_field_round_trips_and_is_absent_when_there_is_none():
    net = NetworkFrame(np.array([[0, 1], [1, 0], [2, 1]]), np.array([30.3, 0.0, 60.6]))
    for back in (Frame.from_dict(json.loads(json.dumps(_frame(1, net).to_dict()))),
                 decode_frame(encode_frame(_frame(1, net))),
                 decode_frame(encode_frame(_frame(2, net), previous=_frame(1, net)), previous=_frame(1, net))):
        assert back.network is not None
        assert back.network.links.tolist() == [[0, 1], [1, 0], [2, 1]]
        assert np.allclose(back.network.rate, [30.3, 0.0, 60.6], rtol=1e-6)
    plain = _frame(1, None)
    assert "network" not in plain.to_dict() and b'"network"' not in encode_frame(plain)
    assert decode_frame(encode_frame(plain)).network is None


def test_swarmdeck_run_records_the_decentralised_traffic(tmp_path, capsys):
    path = tmp_path / "run.mcap"
    script = decentralised_rendezvous.__file__
    assert main(["run", script, "--robots", "4", "--duration", "1", "--seed", "2", "--record", str(path)]) == 0
    with open_recording(path) as rec:
        frames = [frame for _, frame in rec.frames()]
    assert len(frames) == 31
    nets = [f.network for f in frames]
    assert all(n is not None for n in nets)
    # the cycle on 4 robots: 8 directed links every tick; messages flow once the first broadcasts arrived
    assert all(n.links.shape == (8, 2) for n in nets if n is not None)
    assert sum(float(n.rate.sum()) for n in nets if n is not None) > 0
    with open(path, "rb") as fh:
        topics = [channel.topic for _, channel, _ in make_reader(fh).iter_messages()]
    # the default (packed) Foxglove channels draw the links with the other line scenes, once a recorded second
    assert topics.count("/foxglove/network") == 2
    entities = tmp_path / "entities.mcap"
    assert main(["run", script, "--robots", "4", "--duration", "1", "--seed", "2", "--record", str(entities),
                 "--foxglove-entities"]) == 0
    with open(entities, "rb") as fh:  # one entity per robot: the links every frame, as before
        topics = [channel.topic for _, channel, _ in make_reader(fh).iter_messages()]
    assert topics.count("/foxglove/network") >= 30
