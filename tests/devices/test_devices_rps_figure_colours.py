"""The rps figure's colours are converted once per value, not once per artist per step (issue 28: the plotting
examples' step cost): :class:`~swarmdeck.devices.rps.figure_annotations.Colours` gives the very bytes of the
conversion it replaces (``_rgba``, matplotlib's ``to_rgba_array``) for every colour — names, hex, the colour cycle,
"none", tuples, arrays, colours matplotlib refuses (the same error) — while its memo is kept across calls; a colour
that depends on matplotlib's state (the colour cycle ``"C0"``) follows that state."""
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from swarmdeck.core.bounds import DEFAULT_BOUNDS  # noqa: E402
from swarmdeck.devices.rps.figure_annotations import Colours, _rgba, figure_annotations  # noqa: E402

KEPT = Colours(limit=64)  # one memo across every example: what a run's facade keeps from step to step

unit = st.floats(0.0, 1.0)
component = st.one_of(unit, st.sampled_from([0, 1, -0.0, 1.5, -0.25, float("nan")]),
                      unit.map(np.float32), unit.map(np.float64))
colour = st.one_of(
    st.sampled_from(["red", "r", "k", "tab:blue", "C0", "C3", "C12", "none", "None", "NONE", "#1f77b4", "#abc",
                     "#11223344", "0.5", "not a colour", "", "xkcd:sky blue"]),
    st.tuples(component, component, component),
    st.tuples(component, component, component, component),
    st.tuples(unit, unit),  # rps never draws one; matplotlib reads (colour, alpha) pairs its own way
    st.lists(st.tuples(unit, unit, unit, unit), min_size=0, max_size=3).map(lambda rows: np.array(rows).reshape(-1, 4)),
    st.lists(st.sampled_from(["red", "none", "C1"]), max_size=3),
)
alpha = st.one_of(st.none(), unit, st.sampled_from([0, 1, 2.0, -1.0, float("nan")]))


def _outcome(call):
    try:
        return call()
    except Exception as exc:  # noqa: BLE001 - the same error either way is what is compared
        return (type(exc), str(exc))


@settings(max_examples=300, deadline=None)
@given(colour, alpha)
def test_kept_conversions_are_the_bytes_of_the_conversion_they_replace(c, a):
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # NaN alpha: the cast warns on both paths
        want = _outcome(lambda: _rgba(c, a))
        for _ in range(2):  # a miss, then a hit of the memo
            got = _outcome(lambda: KEPT.rgba(c, a))
            if isinstance(want, tuple):
                assert got == want
            else:
                assert isinstance(got, np.ndarray) and got.dtype == want.dtype and got.shape == want.shape
                assert got.tobytes() == want.tobytes()


def test_the_colour_cycle_is_read_at_every_call():
    kept = Colours()
    first = kept.rgba("C0", None).copy()
    with matplotlib.rc_context({"axes.prop_cycle": matplotlib.cycler(color=["#00ff00"])}):
        assert kept.rgba("C0", None).tolist() == [[0, 255, 0, 255]]
    assert kept.rgba("C0", None).tolist() == first.tolist()


def test_a_kept_memo_draws_what_a_fresh_one_draws_step_after_step():
    fig, ax = plt.subplots()
    try:
        ax.set_xlim(-1.7, 1.7)
        ax.set_ylim(-1.1, 1.1)
        dot, = ax.plot([0.1], [0.2], "o", markerfacecolor="none", markeredgecolor=(0.1, 0.2, 0.3))
        line, = ax.plot([0.0, 0.5], [0.0, 0.5], "-", color="C1", alpha=0.5)
        label = ax.text(0.3, -0.3, "hi", color="m")
        ax.scatter([0.2, -0.2], [0.1, 0.4], c=["red", "blue"])
        kept = Colours(limit=2)  # starts over often: the memo's limit is exercised too
        for k in range(4):
            dot.set_markeredgecolor((0.1 * k, 0.2, 0.3))
            line.set_color(f"C{k}")
            label.set_color(["m", "k", (0.5, 0.5, 0.5), "none"][k])
            a, b = figure_annotations(ax, DEFAULT_BOUNDS, colours=kept), figure_annotations(ax, DEFAULT_BOUNDS)
            for field in ("kinds", "offsets", "vertices", "sizes", "colors", "filled"):
                assert getattr(a, field).tobytes() == getattr(b, field).tobytes(), field
            assert a.texts == b.texts
    finally:
        plt.close(fig)


def test_kept_rows_cannot_be_changed_by_a_caller():
    row = Colours().rgba("red", None)
    with pytest.raises(ValueError):
        row[0, 0] = 1
