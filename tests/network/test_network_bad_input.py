"""Bad messages (issue 28): a message of 10 MB, 10,000 messages in one tick, a message to a robot that does not
exist, a non-serialisable payload, a message to itself — each refused with a clear error naming what was wrong,
counted, and the network (and a decentralised run's loop) goes on."""
from __future__ import annotations

import numpy as np
import pytest

from swarmdeck.devices import Arena
from swarmdeck.devices.decentralised import Decentralised
from swarmdeck.network import DiskTopology, MessageError, Network, NetworkConfig, PayloadError

POS = np.array([[0.0, 0.0], [0.3, 0.0], [0.6, 0.0]])
TEN_MB = b"\0" * (10 * 1024 * 1024)


def _net() -> Network:
    return Network(3, NetworkConfig(topology=DiskTopology(1.0)), positions=POS)


@pytest.mark.parametrize(("send", "error", "words", "counter"), [
    (lambda n: n.send(0, 1, TEN_MB), PayloadError, ["robot 0", "10485760 bytes", "4096"], "refused:too_big"),
    (lambda n: n.send(0, 1, {"big": np.zeros(2_000_000)}), PayloadError, ["robot 0", "exceeds"], "refused:too_big"),
    (lambda n: n.send(0, 1, list(range(10_000_000))), PayloadError, ["10000000 items", "exceeds"], "refused:too_big"),
    (lambda n: n.send(0, 7, "hi"), MessageError, ["robot 0", "receiver 7 does not exist", "0..2"], "refused:unknown_robot"),
    (lambda n: n.send(-1, 0, "hi"), MessageError, ["sender -1 does not exist"], "refused:unknown_robot"),
    (lambda n: n.send(0, "1", "hi"), MessageError, ["receiver must be a robot index"], "refused:unknown_robot"),
    (lambda n: n.send(0, 1, {"f": open}), PayloadError, ["robot 0", "payload['f']", "not serialisable"], "refused:unserialisable"),
    (lambda n: n.send(0, 1, {1: "int key"}), PayloadError, ["keys must be str"], "refused:unserialisable"),
    (lambda n: n.send(0, 1, np.array(["a"], dtype=object)), PayloadError, ["dtype object"], "refused:unserialisable"),
    (lambda n: n.send(2, 2, "me"), MessageError, ["robot 2", "to itself"], "refused:to_itself"),
])
def test_a_bad_message_is_refused_named_and_counted(send, error, words, counter):
    net = _net()
    with pytest.raises(error) as info:
        send(net)
    assert all(w in str(info.value) for w in words), str(info.value)
    assert net.stats[counter] == 1 and net.refused == 1 and str(info.value) in net.errors
    net.send(0, 1, "still works")
    net.step(POS)
    assert [m.payload for m in net.inbox(1)] == ["still works"]


def test_ten_thousand_messages_in_one_tick():
    net = _net()
    refused = 0
    for k in range(10_000):
        try:
            net.send(0, 1 + k % 2, k)
        except MessageError as exc:
            refused += 1
            assert "more than 64 messages in one tick" in str(exc) and "robot 0" in str(exc)
    cap = net.config.max_messages_per_tick
    assert refused == 10_000 - cap and net.stats["refused:too_many"] == refused
    net.step(POS)
    assert len(net.inbox(1)) + len(net.inbox(2)) == cap
    net.send(0, 1, "next tick")  # the count is per tick
    net.step(POS)
    assert [m.payload for m in net.inbox(1)] == ["next tick"]


def test_bad_messages_from_decentralised_controllers_never_stop_the_run():
    """Each robot's controller sends one kind of bad message every tick; the run goes on, every refusal counted."""
    bad = {
        0: lambda v: v.send(1, TEN_MB),
        1: lambda v: [v.send(0, k) for k in range(10_000)],
        2: lambda v: v.send(17, "to nobody"),
        3: lambda v: v.send(0, object()),
        4: lambda v: v.send(4, "to myself"),
    }

    def robot(i, view):
        view.state["ran"] = view.state.get("ran", 0) + 1
        if i in bad:
            bad[i](view)
        return np.array([0.01, 0.0])

    arena = Arena(6, config=None)
    run = Decentralised(arena, robot, NetworkConfig(topology=DiskTopology(5.0)))
    for _ in range(3):
        run.step()
    assert run.tick == 3 and all(s["ran"] == 3 for s in run.states)
    for reason in ("too_big", "too_many", "unknown_robot", "unserialisable", "to_itself"):
        assert run.errors[f"message:{reason}"] == 3, reason
        assert run.network.stats[f"refused:{reason}"] == 3, reason
    # robot 1's first 64 messages per tick went out (its 65th raised); the robots that raised stood still
    assert run.network.stats["delivered"] == 3 * 64  # latency 0: each tick's 64 arrive at its end
    assert any("robot 4" in e and "itself" in e for e in run.events)
    moved = np.abs(run.last_commands).sum(axis=1) > 0
    assert moved.tolist() == [False, False, False, False, False, True]
