"""A file another tool re-chunked so finely that some chunks hold no keyframe (one frame per chunk):
seeking straight into any chunk still gives its frame — the reader looks back through the chunks
before to the last keyframe. Before: it looked back one chunk only and returned an earlier frame."""
from __future__ import annotations

from mcap.reader import make_reader
from mcap.writer import Writer
from recording_synth import simulated_frames

from swarmdeck.console.recording.reader import open_recording
from swarmdeck.console.recording.recorder import Recorder, RecorderConfig
from swarmdeck.console.recording.schemas import PROFILE


def test_seeking_into_a_chunk_without_a_keyframe_gives_its_frame(tmp_path):
    frames = list(simulated_frames(n_robots=6, n_ticks=24, dt=1 / 30))
    src_path = tmp_path / "src.mcap"
    with Recorder(src_path, config=RecorderConfig(foxglove=False)) as rec:  # keyframes every 8 frames
        for f in frames:
            rec.write_frame(f)
    path = tmp_path / "rechunked.mcap"
    with open(src_path, "rb") as src, open(path, "wb") as fh:
        reader = make_reader(src)
        w = Writer(fh, chunk_size=1)  # every message its own chunk
        w.start(profile=PROFILE, library="another tool")
        for m in reader.iter_metadata():
            w.add_metadata(m.name, m.metadata)
        ids: dict[int, int] = {}
        for schema, channel, message in reader.iter_messages(log_time_order=False):
            if channel.id not in ids:
                ids[channel.id] = w.register_channel(channel.topic, channel.message_encoding,
                                                     w.register_schema(schema.name, schema.encoding, schema.data))
            w.add_message(ids[channel.id], log_time=message.log_time, data=message.data,
                          publish_time=message.publish_time)
        w.finish()
    for want in (frames[5], frames[7], frames[13], frames[23]):  # predicted frames, 2+ chunks after a keyframe
        with open_recording(path) as r:  # a fresh reader: nothing decoded before the seek
            _, got = r.frame_at(want.time - frames[0].time + 1e-4)
            assert got.tick == want.tick and got.poses.tobytes() == want.poses.tobytes() and not r.warnings
