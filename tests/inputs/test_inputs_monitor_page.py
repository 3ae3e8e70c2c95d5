"""The `inputs monitor` page has a bounded size whatever arrives: at most a screenful of
sources and contacts, the rest summarised, long error texts cut (after a fuzz it had
1,167 lines)."""
from __future__ import annotations

from swarmdeck.inputs import InputHub, InputSource, ListenerConfig
from swarmdeck.inputs import oscbuild as ob
from swarmdeck.inputs.monitor import render


def busy_snapshot():
    src = InputSource(ListenerConfig(max_reported_sources=1000))  # the page must cap on its own too
    t = 0.0
    long_junk = ob.message("/tuio/2Dcur", "s" + "f" * 300, "alive", *([0.5] * 300))
    for k in range(1100):
        t += 0.001
        peer = (f"10.{k // 250}.{k % 250}.3", 7)
        src.feed(b"garbage!", peer, t)
        src.feed(long_junk, peer, t)
    for s in range(5):  # five tables with 40 fingers each
        ids = list(range(40))
        src.feed(ob.tuio_bundle("2Dcur", ids, ob.cursor_sets([(i, 0.01 * i, 0.5) for i in ids]), fseq=1,
                                source=f"table{s}"), ("10.9.0.1", 1), t)
    return InputHub([src]).poll(t)


def test_page_is_capped_and_summarised():
    snap = busy_snapshot()
    assert len(snap.contacts) == 200 and len(snap.health) > 1000
    page = render(snap, ("udp://0.0.0.0:3333",))
    lines = page.splitlines()
    assert len(lines) <= 70
    assert max(len(ln) for ln in lines) <= 160
    assert "more sources" in page and "more contacts" in page
    assert "table1 40" in page and "table0 20" in page  # contacts left out are summarised by source
    (tot,) = [ln for ln in lines if ln.startswith("listener tuio")]
    assert "not_osc 1100" in tot and "bad_args 1100" in tot


def test_small_page_is_unchanged_in_content():
    src = InputSource()
    src.feed(ob.tuio_bundle("2Dcur", [3], ob.cursor_sets([(3, 0.5, 0.5)]), fseq=1, source="TuioPad@10.0.0.2"),
             ("10.0.0.2", 40000), 0.0)
    page = render(InputHub([src]).poll(0.1))
    assert "more" not in page and "udp://10.0.0.2/TuioPad@10.0.0.2" in page and "id 3" in page
    empty = render(InputHub([InputSource()]).poll(0.0))
    assert "nothing received yet" in empty
