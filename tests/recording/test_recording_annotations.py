"""What an experiment drew round-trips through the recording (issue 29 item 3): ``Frame.annotations`` through
``Frame.to_dict``/``from_dict`` (format 1), the codec's keyframes and predicted frames (format 3) and an MCAP
file read back; a frame without annotations writes no key (older recordings read as nothing drawn), and
malformed annotations in a file are a clear error naming them."""
import json

import numpy as np
import pytest

from swarmdeck.console.recording.codec import decode_frame, encode_frame, frame_message
from swarmdeck.console.recording.reader import Recording
from swarmdeck.console.recording.recorder import Recorder
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.core.annotations import CIRCLE, POINT, POLYGON, POLYLINE, TEXT, Annotations

ANN = Annotations(kinds=[POINT, POLYLINE, CIRCLE, POLYGON, TEXT], offsets=[0, 1, 4, 5, 8, 9],
                  vertices=[[0.1, 0.2], [0, 0], [0.5, 0.1 + 1e-13], [1.0, 0.5], [-0.3, 0.3], [-1, -0.5], [-0.5, -0.5],
                            [-0.75, 0.0], [0.0, 0.8]],
                  sizes=[0.02, 0.01, 0.15, 0.01, 0.08], colors=[[255, 0, 0, 128], [0, 255, 0, 255], [0, 0, 255, 10],
                                                              [1, 2, 3, 4], [0, 0, 0, 255]],
                  filled=[True, False, True, False, False], texts=("", "", "", "", "hello ✓"))


def frame(tick, annotations=None):
    n = 3
    poses = np.array([[-1.0, 0.0, 0.0], [0.0, 0.5, 1.0], [1.0, -0.5, 2.0]]) + 0.01 * tick
    return Frame(tick=tick, time=tick * 0.033, poses=poses, ids=np.arange(n), nominal=np.zeros((n, 2)),
                 safe=np.zeros((n, 2)), v=np.full(n, 0.1), w=np.zeros(n), annotations=annotations)


def same(a, b):
    assert b is not None
    for name in ("kinds", "offsets", "vertices", "sizes", "colors", "filled"):
        assert getattr(a, name).tolist() == getattr(b, name).tolist(), name
    assert a.texts == b.texts


def test_frame_dict_and_codec_round_trip_exactly():
    f = frame(0, ANN)
    same(ANN, Frame.from_dict(json.loads(json.dumps(f.to_dict()))).annotations)
    same(ANN, decode_frame(encode_frame(f)).annotations)  # a keyframe
    g = frame(1, ANN)
    same(ANN, decode_frame(encode_frame(g, previous=f), previous=f).annotations)  # a predicted frame


def test_no_annotations_no_key_and_old_frames_read_as_nothing_drawn():
    f = frame(0)
    assert "annotations" not in f.to_dict() and "annotations" not in frame_message(f)
    assert "annotations" not in frame_message(frame(0, Annotations()))  # an empty drawing is nothing drawn
    assert decode_frame(encode_frame(f)).annotations is None
    assert Frame.from_dict(f.to_dict()).annotations is None


def test_malformed_annotations_in_a_file_name_the_field():
    d = frame_message(frame(0, ANN))
    d["annotations"]["texts"] = "not a list"
    with pytest.raises(ValueError, match="annotations.texts"):
        decode_frame(d)
    d = frame(0, ANN).to_dict()
    d["annotations"]["offsets"] = [0, 1]
    with pytest.raises(ValueError, match="offsets"):
        Frame.from_dict(d)


def test_an_mcap_file_keeps_every_frames_drawing(tmp_path):
    path = tmp_path / "r.mcap"
    rec = Recorder(path, {})
    frames = [frame(k, ANN if k % 3 else None) for k in range(10)]
    for f in frames:
        rec.write_frame(f)
    rec.close()
    read = [f for _, f in Recording(path).frames()]
    assert len(read) == 10
    for f, g in zip(frames, read):
        if f.annotations is None:
            assert g.annotations is None
        else:
            same(f.annotations, g.annotations)
    assert Recording(path).message_counts()["/foxglove/annotations"] >= 1
