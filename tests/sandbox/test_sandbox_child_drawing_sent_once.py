"""The sandboxed child encodes a drawing once: while the Arena's annotator hands it the same (read-only) drawing
tick after tick, nothing is encoded or sent again; a new drawing is sent before the next commands
(console/sandbox/child.py ``PipeRobots.send_annotations``)."""
from __future__ import annotations

import os

import numpy as np

from swarmdeck.console.sandbox import child
from swarmdeck.console.sandbox.protocol import MESSAGE, FrameReader, decode, encode_poses, write_frame
from swarmdeck.core.annotations import Annotations
from swarmdeck.core.annotator import Annotator
from swarmdeck.core.kinematics import GritsBotParams
from swarmdeck.devices.simulator import ArenaConfig


def test_an_unchanged_drawing_is_encoded_once_and_a_new_one_is_sent(monkeypatch) -> None:
    encoded = []
    real = child.encode_annotations
    monkeypatch.setattr(child, "encode_annotations", lambda ann: encoded.append(ann) or real(ann))
    to_child_r, to_child_w = os.pipe()
    from_child_r, from_child_w = os.pipe()
    try:
        write_frame(to_child_w, encode_poses(0, 0.0, np.zeros((2, 3))))  # the trusted side's first poses
        robots = child.PipeRobots(child.Link(to_child_r, from_child_w), 2, None, config=ArenaConfig(),
                                  params=GritsBotParams())
        annotator = Annotator()
        annotator.circles([(0.1, 0.2)], 0.05)
        first = annotator.collect(0.0)
        assert annotator.collect(0.033) is first  # the annotator's cache: one object while nothing changed
        before = len(encoded)
        for _ in range(5):
            robots.send_annotations(first)
        assert len(encoded) == before + 1, "the same drawing was encoded again"
        second = Annotations.concat([first, first])
        robots.send_annotations(second)
        assert len(encoded) == before + 2
        os.close(from_child_w)
        from_child_w = -1
        reader = FrameReader(from_child_r)
        kinds = []
        while reader.feed():
            pass
        while (frame := reader.next()) is not None:
            kinds.append(decode(frame[1])["t"] if frame[0] == MESSAGE else frame[0])
        assert kinds == ["arena", "draw", "draw"], kinds
    finally:
        for fd in (to_child_r, to_child_w, from_child_r, from_child_w):
            if fd >= 0:
                os.close(fd)
