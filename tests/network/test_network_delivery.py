"""Messages arrive over the topology's links, after the configured latency, as copies the receiver cannot use
to reach the sender's object; the topologies agree with brute force (REFERENCE.md §16)."""
from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.core.graphs import cycle_laplacian
from swarmdeck.network import DiskTopology, FixedTopology, KNearestTopology, Network, NetworkConfig

LINE = np.array([[0.0, 0.0], [0.3, 0.0], [0.6, 0.0], [2.0, 0.0]])


def test_a_message_is_in_the_inbox_after_latency_ticks():
    for latency in (0, 1, 3):
        net = Network(4, NetworkConfig(topology=DiskTopology(0.5), latency=latency), positions=LINE)
        net.send(0, 1, "hello")
        arrivals = []
        for tick in range(6):
            net.step(LINE)
            arrivals += [(tick, m.sender, m.sent_tick, m.payload) for m in net.inbox(1)]
        assert arrivals == [(latency, 0, 0, "hello")]  # read in tick latency + 1, i.e. after the step of tick latency


def test_jitter_spreads_arrivals_within_latency_plus_jitter():
    net = Network(2, NetworkConfig(topology=DiskTopology(1.0), latency=2, jitter=3, seed=7), positions=LINE[:2])
    for _ in range(40):
        net.send(0, 1, 1)
    delays = []
    for tick in range(10):
        net.step(LINE[:2])
        delays += [tick - m.sent_tick for m in net.inbox(1)]
    assert len(delays) == 40 and set(delays) == {2, 3, 4, 5}


def test_only_linked_robots_hear_each_other_and_broadcast_reaches_every_neighbour():
    net = Network(4, NetworkConfig(topology=DiskTopology(0.5)), positions=LINE)
    assert net.neighbours(1).tolist() == [0, 2] and net.neighbours(3).tolist() == []
    assert net.broadcast(1, {"x": 1.5}) == 2
    net.send(0, 3, "far away")  # no link 0 -> 3: queued, then unreachable
    net.step(LINE)
    assert [m.payload for m in net.inbox(0)] == [{"x": 1.5}] and [m.payload for m in net.inbox(2)] == [{"x": 1.5}]
    assert net.inbox(3) == () and net.stats["unreachable"] == 1 and net.stats["delivered"] == 2
    traffic = net.traffic()
    assert traffic.links.tolist() == [[0, 1], [1, 0], [1, 2], [2, 1]]
    assert traffic.messages.tolist() == [0, 1, 1, 0] and (traffic.bytes[traffic.messages > 0] > 0).all()


def test_the_receiver_gets_a_copy():
    payload = {"p": np.array([1.0, 2.0]), "path": [[0, 1], [2, 3]]}
    net = Network(2, NetworkConfig(topology=DiskTopology(1.0)), positions=LINE[:2])
    net.send(0, 1, payload)
    payload["p"][0] = 99.0  # the sender changes its object after sending: the message does not change
    net.step(LINE[:2])
    (first,) = net.inbox(1)
    first.payload["p"][1] = -1.0
    first.payload["path"].append("mine")
    (again,) = net.inbox(1)  # every read is a fresh copy
    assert again.payload["p"].tolist() == [1.0, 2.0] and again.payload["path"] == [[0, 1], [2, 3]]
    assert payload["p"].tolist() == [99.0, 2.0] and payload["path"] == [[0, 1], [2, 3]]


def test_the_fixed_graph_is_the_papers_g_whatever_the_positions():
    topo = FixedTopology.from_laplacian(cycle_laplacian(5))
    far = np.column_stack((np.arange(5) * 10.0, np.zeros(5)))
    links = topo.links(far)
    assert {tuple(x) for x in links.tolist()} == {(i, (i + 1) % 5) for i in range(5)} | {((i + 1) % 5, i) for i in range(5)}


positions = st.integers(2, 40).flatmap(
    lambda n: st.lists(st.tuples(st.floats(-1.6, 1.6), st.floats(-1.0, 1.0)), min_size=n, max_size=n))


@settings(max_examples=40)
@given(positions, st.floats(0.05, 1.5), st.integers(1, 6))
def test_proximity_topologies_match_brute_force(pts, delta, k):
    p = np.array(pts, dtype=float)
    n = len(p)
    d = np.linalg.norm(p[:, None] - p[None], axis=2)  # brute force, test only
    disk = {(i, j) for i in range(n) for j in range(n) if i != j and d[i, j] <= delta}
    assert {tuple(x) for x in DiskTopology(delta).links(p).tolist()} == disk
    links = KNearestTopology(k).links(p)
    assert not np.any(links[:, 0] == links[:, 1])
    counts = np.bincount(links[:, 1], minlength=n)
    assert (counts == min(k, n - 1)).all()
    for s, r in links.tolist():  # every chosen sender is no farther than the receiver's k-th nearest other robot
        others = np.sort(np.delete(d[r], r))
        assert d[r, s] <= others[min(k, n - 1) - 1] + 1e-12
    assert (np.lexsort((links[:, 1], links[:, 0])) == np.arange(len(links))).all()


arrays = st.sampled_from(["<f8", ">f4", "<i8", ">i2", "|u1", "|b1", "<f2"]).flatmap(
    lambda dt: st.lists(st.integers(0, 3), min_size=0, max_size=3).map(
        lambda shape: np.asarray(np.arange(int(np.prod(shape)), dtype=np.int64).reshape(shape) % 7).astype(dt)))


@settings(max_examples=40)
@given(arrays, st.booleans())
def test_arrays_arrive_with_their_values_shape_and_kind(a, transpose):
    sent = a.T if transpose else a  # non-contiguous views travel too
    net = Network(2, NetworkConfig(topology=DiskTopology(1.0)), positions=LINE[:2])
    net.send(0, 1, {"a": sent, "n": [sent]})
    net.step(LINE[:2])
    (m,) = net.inbox(1)
    for got in (m.payload["a"], m.payload["n"][0]):
        assert got.shape == sent.shape and got.dtype.kind == sent.dtype.kind and got.dtype.itemsize == sent.dtype.itemsize
        assert np.array_equal(got, sent) and got.flags.writeable
