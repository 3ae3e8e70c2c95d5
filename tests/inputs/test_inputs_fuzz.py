"""Fuzzing the datagram path: 100 000 mutated datagrams (hypothesis draws the
seeds, 500 mutations each) plus hypothesis-built TUIO messages with arbitrary
argument types. Nothing may raise, nothing may hang (python-osc loops forever on
a negative bundle element size unless it is rejected first), every datagram is
counted, no decoder hits an internal error, and the listener still works after."""
from __future__ import annotations

import struct

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from swarmdeck.inputs import PRESETS, InputSource, ListenerConfig
from swarmdeck.inputs import oscbuild as ob

PEER = ("10.9.9.9", 1)
EXAMPLES = 200
PER_EXAMPLE = 500  # 200 × 500 = 100 000 inputs

CORPUS = [
    ob.tuio_bundle("2Dcur", [1, 2], ob.cursor_sets([(1, 0.1, 0.2), (2, 0.3, 0.4)]), fseq=5, source="a@b"),
    ob.tuio_bundle("2Dobj", [3], [(3, 7, 0.5, 0.5, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0)], fseq=6),
    ob.tuio_bundle("2Dblb", [4], [(4, 0.5, 0.5, 0.0, 0.1, 0.1, 0.01, 0.0, 0.0, 0.0, 0.0, 0.0)], fseq=-1),
    ob.tuio2_frame(3, "REAC:0@0x1", [("ptr", "iii" + "f" * 6, [1, 0, 0, 0.5, 0.5, 0.0, 0.0, 0.01, 1.0]),
                                     ("bnd", "i" + "f" * 6, [1, 0.5, 0.5, 0.0, 0.1, 0.1, 0.01])], [1], time=1.7e9),
    ob.bundle(ob.bundle(ob.message("/tuio/2Dcur", "si", "alive", 1)), ob.message("/finger0-1", "siifff", "m", 0, 1, 1.0, 2.0, 3.0)),
    ob.message("/leap/left", "fff", 10.0, 200.0, -30.0),
    ob.message("/tuio/2Dcur", "sifffff", "set", 1, 0.5, 0.5, 0.0, 0.0, 0.0),
]
TAGS = b"ifsdbhtTFNcSmr[]x,\x00"


def mutate(rng: np.random.Generator, data: bytes) -> bytes:
    b = bytearray(data)
    op = int(rng.integers(0, 8))
    if op == 0 and b:  # flip bytes
        for _ in range(int(rng.integers(1, 9))):
            b[int(rng.integers(0, len(b)))] = int(rng.integers(0, 256))
    elif op == 1:  # truncate (keep or break 4-byte alignment)
        b = b[: int(rng.integers(0, len(b) + 1))]
    elif op == 2:  # append junk
        b += rng.integers(0, 256, int(rng.integers(1, 64)), dtype=np.uint8).tobytes()
    elif op == 3 and len(b) >= 8:  # overwrite an aligned int32 with an edge value
        i = 4 * int(rng.integers(0, len(b) // 4))
        v = [-1, 0, 1, 3, 4, -4, 0x7FFFFFFF, -0x80000000, len(b), len(b) - i][int(rng.integers(0, 10))]
        b[i:i + 4] = struct.pack(">i", v)
    elif op == 4 and b:  # replace a type tag character
        j = b.find(b",")
        if j >= 0 and j + 1 < len(b):
            b[j + 1 + int(rng.integers(0, max(1, min(8, len(b) - j - 1))))] = TAGS[int(rng.integers(0, len(TAGS)))]
    elif op == 5:  # pure noise, aligned
        b = bytearray(rng.integers(0, 256, 4 * int(rng.integers(0, 40)), dtype=np.uint8).tobytes())
    elif op == 6:  # splice two corpus entries
        other = CORPUS[int(rng.integers(0, len(CORPUS)))]
        cut = int(rng.integers(0, len(b) + 1))
        b = b[:cut] + other[int(rng.integers(0, len(other) + 1)):]
    else:  # bundle header around junk
        b = bytearray(b"#bundle\x00" + bytes(8) + struct.pack(">i", int(rng.integers(-8, 64))) + bytes(b))
    return bytes(b)


def _check_health(src: InputSource, fed: int, t: float) -> None:
    health = src.health(t)
    assert sum(h.datagrams for h in health if h.kind == "peer") == fed
    for h in health:
        assert "internal_error" not in h.errors, h.last_error
        assert "hook_error" not in h.errors


@settings(max_examples=EXAMPLES, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**63 - 1))
def test_hundred_thousand_mutated_datagrams_never_break_the_listener(seed):
    rng = np.random.default_rng(seed)
    streams = PRESETS["manososc"] + PRESETS["ultraleap-osc-sender"]
    src = InputSource(ListenerConfig(streams=streams))
    t = 0.0
    for _ in range(PER_EXAMPLE):
        data = mutate(rng, CORPUS[int(rng.integers(0, len(CORPUS)))])
        t += 0.001
        src.feed(data, PEER, t)
        if rng.random() < 0.02:
            src.poll(t)
    _check_health(src, PER_EXAMPLE, t)
    src.feed(ob.tuio_bundle("2Dcur", [77], ob.cursor_sets([(77, 0.5, 0.5)]), fseq=1, source="after@fuzz"), ("1.2.3.4", 9), t)
    assert any(c.id == 77 and c.source.endswith("after@fuzz") for c in src.poll(t).contacts)


_arg = st.one_of(
    st.tuples(st.just("i"), st.integers(-2**31, 2**31 - 1)),
    st.tuples(st.just("f"), st.floats(width=32, allow_nan=True, allow_infinity=True)),
    st.tuples(st.just("d"), st.floats(allow_nan=True)),
    st.tuples(st.just("h"), st.integers(-2**63, 2**63 - 1)),
    st.tuples(st.just("s"), st.sampled_from(["set", "alive", "fseq", "source", "", "x"])),
    st.tuples(st.sampled_from("TFN"), st.none()),
)


@settings(max_examples=300, deadline=None)
@given(address=st.sampled_from(["/tuio/2Dcur", "/tuio/2Dobj", "/tuio/2Dblb", "/tuio/25Dcur", "/tuio2/frm",
                                "/tuio2/ptr", "/tuio2/tok", "/tuio2/bnd", "/tuio2/alv", "/finger0-1", "/leap/right"]),
       args=st.lists(_arg, max_size=16), bundled=st.booleans())
def test_arbitrary_argument_types_and_counts_are_rejected_or_accepted_never_raised(address, args, bundled):
    src = InputSource(ListenerConfig(streams=PRESETS["manososc"] + PRESETS["ultraleap-osc-sender"]))
    tags = "".join(t for t, _ in args)
    m = ob.message(address, tags, *[v for t, v in args if t not in "TFN"])
    src.feed(ob.bundle(m) if bundled else m, PEER, 0.0)
    snap = src.poll(0.0)
    _check_health(src, 1, 0.0)
    for c in snap.contacts:  # whatever got through is finite and inside the arena
        assert np.all(np.isfinite(c.position)) and np.all(np.isfinite(c.velocity))
        assert -1.6 <= c.position[0] <= 1.6 and -1.0 <= c.position[1] <= 1.0
