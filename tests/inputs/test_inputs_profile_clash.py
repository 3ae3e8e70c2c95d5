"""A cursor and an object (or a TUIO 2.0 pointer and token) of one source with the
same session id: TUIO session ids are unique per source, so this is a sender bug.
The cursor stays the contact; the clash is counted with a message naming the
profiles (the object used to vanish silently). A blob sharing a cursor's id still
sizes it (TuioPad), without a clash."""
from __future__ import annotations

from swarmdeck.inputs import InputSource
from swarmdeck.inputs import oscbuild as ob

PEER = ("10.0.0.2", 50000)


def clash_bundle(fseq: int) -> bytes:
    return ob.bundle(
        *ob.tuio_messages("2Dcur", [5], ob.cursor_sets([(5, 0.25, 0.5)]), fseq=fseq, source="mixed@1"),
        *ob.tuio_messages("2Dobj", [5], [(5, 7, 0.75, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)], fseq=fseq,
                          source="mixed@1"))


def test_cursor_and_object_with_one_session_id_are_counted_as_a_clash():
    src = InputSource()
    for k in range(3):
        src.feed(clash_bundle(k + 1), PEER, 0.1 * k)
    snap = src.poll(0.2)
    assert [(c.id, c.kind) for c in snap.contacts] == [(5, "cursor")]
    (h,) = [h for h in snap.health if h.name == "udp://10.0.0.2/mixed@1"]
    assert h.errors == {"id_clash": 3}
    assert "2Dobj session 5 is also a 2Dcur session" in h.last_error


def test_tuio2_pointer_and_token_with_one_id_are_counted():
    ptr = ("ptr", "iii" + "f" * 6, [4, 0, 0, 0.5, 0.5, 0.0, 0.0, 0.01, 1.0])
    tok = ("tok", "iii" + "f" * 3, [4, 0, 9, 0.2, 0.2, 0.0])
    src = InputSource()
    src.feed(ob.tuio2_frame(1, "REAC:0@0x1", [ptr, tok], [4]), PEER, 0.0)
    snap = src.poll(0.0)
    assert [(c.id, c.kind) for c in snap.contacts] == [(4, "pointer")]
    (h,) = [h for h in snap.health if h.kind == "tuio2"]
    assert h.errors == {"id_clash": 1} and "tok session 4 is also a ptr session" in h.last_error


def test_a_blob_sizing_a_cursor_is_not_a_clash():
    blob = [(5, 0.25, 0.5, 0.0, 0.1, 0.1, 0.01, 0.0, 0.0, 0.0, 0.0, 0.0)]
    data = ob.bundle(*ob.tuio_messages("2Dcur", [5], ob.cursor_sets([(5, 0.25, 0.5)]), fseq=1, source="pad"),
                     *ob.tuio_messages("2Dblb", [5], blob, fseq=1, source="pad"))
    src = InputSource()
    src.feed(data, PEER, 0.0)
    snap = src.poll(0.0)
    (c,) = snap.contacts
    assert c.kind == "cursor" and c.size is not None
    assert not any(h.errors for h in snap.health)
