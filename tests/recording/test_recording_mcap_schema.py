"""The file opens with the mcap package's own reader and every message validates against its channel's JSON Schema."""
from __future__ import annotations

import json

import jsonschema
import pytest
from mcap.reader import make_reader
from recording_synth import simulated_frames

from swarmdeck.console.recording.codec import frame_message
from swarmdeck.console.recording.recorder import Recorder, RecorderConfig
from swarmdeck.console.recording.schemas import CHANNELS, FRAME_SCHEMA_V1, PROFILE, RECORDING_FORMAT


def test_mcap_reader_and_json_schemas(tmp_path):
    path = tmp_path / "s.mcap"
    rec = Recorder(path, {"robots": [0, 1, 2, 3, 4]}, RecorderConfig(chunk_size=10_000))
    for f in simulated_frames(n_robots=5, n_ticks=30, seed=1):
        rec.write_frame(f)
        rec.write_datagram(b"/tuio/2Dcur\x00", ("10.0.0.2", 3333), "udp", f.time)
    rec.write_event(1.0, "operator", "e-stop")
    rec.close()

    with open(path, "rb") as fh:
        reader = make_reader(fh)
        assert reader.get_header().profile == PROFILE
        summary = reader.get_summary()
        assert summary is not None and len(summary.chunk_indexes) >= 2
        assert all(ci.compression == "zstd" for ci in summary.chunk_indexes)
        meta = {m.name: m.metadata for m in reader.iter_metadata()}
        assert json.loads(meta["swarmdeck"]["recording_format"]) == RECORDING_FORMAT == 3
        counts: dict[str, int] = {}
        validators = {}
        for schema, channel, message in reader.iter_messages():
            if channel.topic not in CHANNELS:  # Foxglove's channels: tests/recording/test_foxglove_channels.py
                continue
            assert channel.message_encoding == "json" and schema.encoding == "jsonschema"
            if channel.topic not in validators:
                declared = json.loads(schema.data)
                assert declared == CHANNELS[channel.topic][1]
                jsonschema.Draft202012Validator.check_schema(declared)
                validators[channel.topic] = jsonschema.Draft202012Validator(declared)
            validators[channel.topic].validate(json.loads(message.data))
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
    assert counts["/swarmdeck/frame"] == 30 and counts["/swarmdeck/datagram"] == 30
    assert counts["/swarmdeck/config"] == 1 and counts["/swarmdeck/event"] >= 1


def test_schema_rejects_a_malformed_frame():
    schema = CHANNELS["/swarmdeck/frame"][1]
    f = next(simulated_frames(n_robots=3, n_ticks=1))
    frame = frame_message(f)
    jsonschema.validate(frame, schema)
    for bad in (dict(frame, poses=f.poses.tolist()),  # a plain list where the binary array belongs
                dict(frame, poses={**frame["poses"], "nd": ">f8"})):  # big-endian
        with pytest.raises(jsonschema.ValidationError):
            jsonschema.validate(bad, schema)
    # format 1 (Frame.to_dict) keeps its own schema
    old = f.to_dict()
    jsonschema.validate(old, FRAME_SCHEMA_V1)
    with pytest.raises(jsonschema.ValidationError):
        jsonschema.validate(dict(old, poses=[[0.0, 0.0]] * 3), FRAME_SCHEMA_V1)  # (N, 2) instead of (N, 3)
