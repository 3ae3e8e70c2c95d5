"""The rps figure's primitives are joined once per figure (issue 28: the plotting examples' step cost): a primitive
remembered on its own (``_Builder.one``, what most artists give) joins into the very arrays the general path
(``_Builder.add`` with one primitive) gives, in any mix with batches of several (markers, scatter)."""
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.core.annotations import CIRCLE, POINT, POLYGON, POLYLINE, TEXT
from swarmdeck.devices.rps.figure_annotations import _Builder

colour = st.tuples(*[st.integers(0, 255)] * 4).map(lambda c: np.array([c], dtype=np.uint8))
#: vertex counts each kind takes
COUNTS = {CIRCLE: (1, 1), TEXT: (1, 1), POINT: (1, 1), POLYLINE: (2, 4), POLYGON: (3, 5)}


def vertices(kind):
    lo, hi = COUNTS[kind]
    return st.integers(lo, hi).flatmap(lambda k: st.lists(st.tuples(st.floats(-2, 2), st.floats(-1, 1)), min_size=k,
                                                          max_size=k)).map(lambda v: np.array(v, dtype=float))


single = st.sampled_from(sorted(COUNTS)).flatmap(lambda kind: st.tuples(
    st.just(kind), vertices(kind), st.one_of(st.floats(0, 1), st.floats(0, 1).map(np.float64)),
    st.one_of(colour, colour.map(lambda c: c[0]), st.just(np.zeros((0, 4), np.uint8))), st.booleans(),
    st.text(max_size=3)))
batch = st.integers(2, 4).flatmap(lambda k: st.tuples(
    st.lists(st.tuples(st.floats(-2, 2), st.floats(-1, 1)), min_size=k, max_size=k).map(lambda v: np.array(v)),
    st.one_of(st.floats(0, 1), st.lists(st.floats(0, 1), min_size=k, max_size=k).map(np.array)), colour,
    st.booleans()))


@settings(max_examples=150, deadline=None)
@given(st.lists(st.one_of(single.map(lambda s: ("one", s)), batch.map(lambda b: ("batch", b))), min_size=1,
                max_size=8))
def test_one_primitive_joins_as_the_general_path_does(pieces):
    fast, general = _Builder(), _Builder()
    for how, piece in pieces:
        if how == "one":
            kind, xy, size, c, filled, text = piece
            fast.one(kind, xy, size, c, filled, text)
            general.add(kind, xy, np.array([len(xy)]), size, c, filled, [text])
        else:
            xy, sizes, c, filled = piece
            for b in (fast, general):
                b.add(POINT, xy, np.ones(len(xy), dtype=np.int64), sizes, c, filled)
    a, b = fast.build(), general.build()
    for field in ("kinds", "offsets", "vertices", "sizes", "colors", "filled"):
        x, y = getattr(a, field), getattr(b, field)
        assert x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes(), field
    assert a.texts == b.texts
