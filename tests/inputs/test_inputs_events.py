"""Invariant: the event stream is consistent with the snapshots — replaying
down/up/lost events on a set reproduces the current contacts after every poll,
whatever the frame order, frame numbers, sources and silences."""
from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.inputs import InputSource
from swarmdeck.inputs import oscbuild as ob

step = st.one_of(
    st.tuples(st.just("frame"), st.sampled_from(["a@1", "b@2", None]), st.sets(st.integers(0, 6), max_size=5),
              st.sets(st.integers(0, 6), max_size=5), st.sampled_from([-1, 0, 1, 2, 3, 50, 51, 300, 301])),
    st.tuples(st.just("wait"), st.floats(0.0, 1.5)),
    st.tuples(st.just("poll")),
)


@settings(max_examples=120, deadline=None)
@given(steps=st.lists(step, max_size=40))
def test_events_replayed_on_a_set_give_the_snapshot(steps):
    src = InputSource()
    model: set = set()
    t = 0.0

    def check():
        snap = src.poll(t)
        for e in snap.events:
            key = (e.source, e.id)
            if e.kind == "down":
                assert key not in model
                model.add(key)
            elif e.kind in ("up", "lost"):
                assert key in model
                model.discard(key)
            elif e.kind == "move":
                assert key in model
            else:
                assert e.kind == "source_lost" and e.id is None
        assert model == {c.key for c in snap.contacts}
        assert len(snap.contacts) == len(model)

    for s in steps:
        if s[0] == "frame":
            _, source, alive, sets, fseq = s
            data = ob.tuio_bundle("2Dcur", sorted(alive), [(i, 0.1 * i, 0.5, 0.0, 0.0, 0.0) for i in sorted(sets)],
                                  fseq=fseq, source=source)
            src.feed(data, ("10.0.0.1", 7), t)
        elif s[0] == "wait":
            t += s[1]
        else:
            check()
    check()
