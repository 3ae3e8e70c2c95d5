"""Reading swarmdeck recordings, tolerant of damage.

:func:`open_recording` checks that the file is an MCAP file written by
swarmdeck in a format this version understands (else :class:`RecordingError`
with a one-line reason), then indexes its chunks: from the MCAP summary when
the file was closed cleanly, else by a linear scan of the data section that
stops at the first damaged record (a crash, ``kill -9``, a truncated copy).
Everything before the damage stays readable; damaged chunks (bad CRC,
undecodable) are skipped and listed in :attr:`Recording.warnings`.

Seeking (:meth:`Recording.frame_at`) bisects the chunk index by time and
decodes one small chunk (a few hundred ms of data), so it costs the same on a
one-hour file as on a one-minute one. Every chunk decodes on its own (frame
format 3 starts each with a keyframe; the frames after it are predicted from
the one before them in the chunk, see ``codec.py``). Times in this API are seconds since the
recording's first frame ("recording time", which is the console's session time
when the recording started with the console: the one time base a user sees and
seeks to, see :mod:`swarmdeck.console.runtime.loop`); ``Frame.time``,
``RecordedEvent.console_t`` and ``RecordedDatagram.t`` keep the loop's clock.
"""
from __future__ import annotations

import json
import os
import struct
from bisect import bisect_right
from collections import OrderedDict
from collections.abc import Iterator
from itertools import accumulate
from pathlib import Path
from typing import Any

from swarmdeck.console.recording.codec import (
    CODEC_FORMAT,
    MissingReference,
    RecordedDatagram,
    RecordedEvent,
    decode_config,
    decode_datagram,
    decode_event,
    decode_frame,
    decode_metadata,
)
from swarmdeck.console.recording.mcap_walk import (
    MAGIC,
    OP_CHANNEL,
    OP_CHUNK,
    OP_HEADER,
    OP_METADATA,
    ChunkRef,
    DamagedChunk,
    McapFile,
    channel_topic,
    parse_record,
)
from swarmdeck.console.recording.schemas import (
    METADATA_NAME,
    PROFILE,
    RECORDING_FORMAT,
    TOPIC_CONFIG,
    TOPIC_DATAGRAM,
    TOPIC_EVENT,
    TOPIC_FRAME,
    TOPIC_OPERATOR,
)
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.core.errors import SwarmdeckError


class RecordingError(SwarmdeckError):
    """The file cannot be played: not MCAP, not a swarmdeck recording, a newer format, unreadable."""


def _parse_header(body: bytes) -> tuple[str, str]:
    h = parse_record(OP_HEADER, body)
    return h.profile, h.library


def _parse_metadata(body: bytes) -> tuple[str, dict[str, str]]:
    m = parse_record(OP_METADATA, body)
    return m.name, dict(m.metadata)


class Recording:
    """An open recording. Use :func:`open_recording`; close with :meth:`close` (or ``with``)."""

    def __init__(self, path: str | os.PathLike[str], cache_chunks: int = 16) -> None:
        self.path = Path(path)
        self.warnings: list[str] = []
        self.indexed = False
        self.profile = ""
        self.library = ""
        self.metadata: dict[str, Any] = {}
        self._channels: dict[int, str] = {}
        self._counts: dict[str, int] | None = None
        self._chunks: list[ChunkRef] = []
        self._starts: list[int] = []
        self._cache: OrderedDict[int, dict[str, list[tuple[int, bytes]]]] = OrderedDict()
        self._cache_size = cache_chunks
        self._frame_cache: OrderedDict[int, list[tuple[int, Frame]]] = OrderedDict()
        try:
            self._f = open(self.path, "rb")
        except OSError as exc:
            raise RecordingError(f"cannot open {self.path}: {exc.strerror or exc}") from None
        try:
            self.size = os.fstat(self._f.fileno()).st_size
            self._mcap = McapFile(self._f, self.size)
            self._check_and_index()
            self._first = self._find_first_frame()
            self._last = self._find_last_frame()
        except RecordingError:
            self._f.close()
            raise

    # ------------------------------------------------------------------ opening
    def _check_and_index(self) -> None:
        mf, size = self._mcap, self.size
        if size < len(MAGIC):
            raise RecordingError(f"{self.path} is not an MCAP file (only {size} bytes)")
        if mf.read(0, len(MAGIC)) != MAGIC:
            raise RecordingError(f"{self.path} is not an MCAP file (no MCAP magic at the start)")
        rec = mf.head(len(MAGIC))
        if rec is None or rec.op != OP_HEADER:
            raise RecordingError(f"{self.path}: damaged MCAP file (no header record after the magic)")
        self.profile, self.library = _parse_header(mf.body(rec))
        if self.profile != PROFILE:
            raise RecordingError(f"{self.path} is an MCAP file from another tool (profile {self.profile!r}, "
                                 f"library {self.library!r}), not a swarmdeck recording")
        pos = rec.end
        meta_found = False
        # Metadata records follow the header directly.
        while True:
            meta = mf.head(pos)
            if meta is None or meta.op != OP_METADATA:
                break
            name, data = _parse_metadata(mf.body(meta))
            if name == METADATA_NAME:
                meta_found = True
                self.metadata.update(decode_metadata(data))
            pos = meta.end
        if not meta_found:
            raise RecordingError(f"{self.path}: damaged swarmdeck recording (no '{METADATA_NAME}' metadata record)")
        fmt = self.metadata.get("recording_format")
        if not isinstance(fmt, int):
            raise RecordingError(f"{self.path}: recording_format missing or not an int ({fmt!r})")
        if fmt > RECORDING_FORMAT:
            raise RecordingError(f"{self.path} was recorded in format {fmt} by a newer swarmdeck "
                                 f"({self.library}); this swarmdeck reads format {RECORDING_FORMAT}: upgrade to play it")
        ffmt = self.metadata.get("frame_format")
        if isinstance(ffmt, int) and ffmt > CODEC_FORMAT:
            raise RecordingError(f"{self.path} holds frames in format {ffmt} from a newer swarmdeck "
                                 f"({self.library}); this swarmdeck reads frame formats up to {CODEC_FORMAT}: upgrade to play it")
        if not self._index_from_summary():
            self._index_by_scan(pos)
        # File order is write order: frames are in time order across chunks. Chunk start times can
        # dip (an input datagram stamped just before the previous chunk's last frame), so bisect
        # on their running maximum.
        self._chunks.sort(key=lambda c: c.offset)
        self._starts = list(accumulate((c.start_ns for c in self._chunks), max))

    def _index_from_summary(self) -> bool:
        """Chunk index, channels and message counts from the MCAP summary (a cleanly closed file).
        False when the summary is missing or inconsistent: the caller scans the file instead."""
        summary, warning = self._mcap.summary()
        if warning:
            self.warnings.append(warning)
        if summary is None:
            return False
        self._channels = dict(summary.channels)
        if summary.channel_counts is not None:
            counts: dict[str, int] = {}
            for cid, c in summary.channel_counts.items():
                topic = summary.channels.get(cid)
                if topic is not None:
                    counts[topic] = counts.get(topic, 0) + c
            self._counts = counts
        self._chunks = list(summary.chunks)
        self.indexed = True
        return True

    def _index_by_scan(self, pos: int) -> None:
        """Walk the data section record by record (reading only chunk headers), up to the first
        damaged or truncated record (:mod:`~swarmdeck.console.recording.mcap_walk`, as ``recover`` does)."""
        mf = self._mcap
        walk = mf.walk(pos)
        for rec in walk:
            if rec.op == OP_CHUNK:
                if rec.length >= 16:
                    start_ns, end_ns = struct.unpack("<QQ", mf.read(rec.body_offset, 16))
                    self._chunks.append(ChunkRef(rec.offset, start_ns, end_ns))
                else:
                    self.warnings.append(f"damaged chunk at byte {rec.offset} skipped")
            elif rec.op == OP_CHANNEL:
                try:
                    cid, topic = channel_topic(mf.body(rec))
                    self._channels[cid] = topic
                except (struct.error, ValueError, UnicodeDecodeError):
                    self.warnings.append(f"damaged channel record at byte {rec.offset} skipped")
        stop = walk.stop
        assert stop is not None
        if stop.reason == "end":
            self.warnings.append("file was not closed cleanly (no summary); recovered by scanning")
        elif stop.reason == "cut":
            self.warnings.append(f"file ends inside a record at byte {stop.offset} of {self.size} (the recording "
                                 "was cut off there); playing everything before it")
        elif stop.reason == "damaged":
            self.warnings.append(f"file damaged at byte {stop.offset} of {self.size}: playing everything before it")
        else:
            self.warnings.append("the MCAP summary is unreadable; recovered by scanning")

    # ------------------------------------------------------------------ chunks
    def _chunk_messages(self, i: int) -> dict[str, list[tuple[int, bytes]]]:
        """Messages of chunk ``i`` by topic as (log_time ns, data); {} if the chunk is damaged."""
        hit = self._cache.get(i)
        if hit is not None:
            self._cache.move_to_end(i)
            return hit
        from mcap.records import Channel, Message

        ref = self._chunks[i]
        out: dict[str, list[tuple[int, bytes]]] = {}
        try:
            records = self._mcap.read_chunk(ref.offset)[1]
        except DamagedChunk as exc:  # damage of any kind: skip the chunk, say so (recover skips it too)
            msg = f"damaged chunk at byte {ref.offset} skipped ({exc})"
            if msg not in self.warnings:
                self.warnings.append(msg)
            records = []
        for r in records:
            if isinstance(r, Channel):
                self._channels[r.id] = r.topic
            elif isinstance(r, Message):
                topic = self._channels.get(r.channel_id)
                if topic is not None:
                    out.setdefault(topic, []).append((r.log_time, r.data))
        for lst in out.values():
            lst.sort(key=lambda m: m[0])
        self._cache[i] = out
        if len(self._cache) > self._cache_size:
            self._cache.popitem(last=False)
        return out

    def _chunk_frames(self, i: int) -> list[tuple[int, Frame]]:
        hit = self._frame_cache.get(i)
        if hit is not None:
            self._frame_cache.move_to_end(i)
            return hit
        frames = self._decode_chunk(i, look_back=True)
        self._frame_cache[i] = frames
        if len(self._frame_cache) > self._cache_size:
            self._frame_cache.popitem(last=False)
        return frames

    def _decode_chunk(self, i: int, look_back: bool) -> list[tuple[int, Frame]]:
        """The frames of chunk ``i``, each format-3 predicted frame decoded from the one before it.
        swarmdeck starts every chunk with a keyframe; in a file another tool re-chunked, the first
        frames of a chunk may be predicted from the last frame of the chunk before: with
        ``look_back`` that one is decoded (itself looking back, through chunks that hold no keyframe,
        to the last keyframe) and used."""
        frames: list[tuple[int, Frame]] = []
        previous: Frame | None = None
        tail: list[Frame | None] = []  # the chunk before's last frame, once looked up
        for ns, data in self._chunk_messages(i).get(TOPIC_FRAME, []):
            try:
                try:
                    previous = decode_frame(data, previous)
                except MissingReference:
                    if frames or previous is not None or not look_back or i == 0:
                        raise
                    if not tail:
                        before = self._chunk_frames(i - 1)
                        tail.append(before[-1][1] if before else None)
                    previous = decode_frame(data, tail[0])
                frames.append((ns, previous))
            except (ValueError, TypeError) as exc:
                previous = None  # the frames predicted from this one are lost up to the next keyframe
                msg = f"undecodable frame at log time {ns} skipped: {exc}"
                if look_back and len(self.warnings) < 100 and msg not in self.warnings:
                    self.warnings.append(msg)
        return frames

    def _find_first_frame(self) -> tuple[int, Frame] | None:
        for i in range(len(self._chunks)):
            fr = self._chunk_frames(i)
            if fr:
                return fr[0]
        return None

    def _find_last_frame(self) -> tuple[int, Frame] | None:
        for i in range(len(self._chunks) - 1, -1, -1):
            fr = self._chunk_frames(i)
            if fr:
                return fr[-1]
        return None

    # ------------------------------------------------------------------ public API
    @property
    def empty(self) -> bool:
        """True when no frame could be read."""
        return self._first is None

    @property
    def damaged(self) -> bool:
        """True when part of the file could not be read (see :attr:`warnings`)."""
        return any("damaged" in w for w in self.warnings)

    @property
    def start_ns(self) -> int:
        """Log time (ns) of the first frame."""
        return self._first[0] if self._first else 0

    @property
    def duration(self) -> float:
        """s from the first to the last frame."""
        if self._first is None or self._last is None:
            return 0.0
        return (self._last[0] - self._first[0]) / 1e9

    @property
    def first_frame(self) -> Frame | None:
        return None if self._first is None else self._first[1]

    @property
    def last_frame(self) -> Frame | None:
        return None if self._last is None else self._last[1]

    @property
    def n_chunks(self) -> int:
        return len(self._chunks)

    def rel(self, ns: int) -> float:
        """Recording time (s since the first frame) of a log time (ns)."""
        return (ns - self.start_ns) / 1e9

    def _ns(self, rel: float) -> int:
        return self.start_ns + round(rel * 1e9)

    def frame_at(self, rel: float) -> tuple[float, Frame] | None:
        """The last frame at or before recording time ``rel`` s (the first frame for ``rel`` ≤ 0):
        ``(its recording time, frame)``; None for an empty recording."""
        if self._first is None:
            return None
        ns = self._ns(rel)
        if ns <= self._first[0]:
            return 0.0, self._first[1]
        i = bisect_right(self._starts, ns) - 1
        while i >= 0:
            frames = self._chunk_frames(i)
            k = bisect_right([f[0] for f in frames], ns) - 1
            if k >= 0:
                # a later chunk may start earlier than this one's frames end (interleaving) — check the next one
                best = frames[k]
                j = i + 1
                while j < len(self._chunks) and self._chunks[j].start_ns <= ns:
                    for fns, fr in self._chunk_frames(j):
                        if best[0] < fns <= ns:
                            best = (fns, fr)
                    j += 1
                return self.rel(best[0]), best[1]
            i -= 1
        return 0.0, self._first[1]

    def frame_after(self, rel: float) -> tuple[float, Frame] | None:
        """The first frame strictly after recording time ``rel`` s, or None at the end."""
        if self._first is None:
            return None
        ns = self._ns(rel)
        if ns < self._first[0]:
            return 0.0, self._first[1]
        i = max(0, bisect_right(self._starts, ns) - 1)
        # chunks before i cannot hold frames after ns unless their range says so
        while i > 0 and self._chunks[i - 1].end_ns > ns:
            i -= 1
        for j in range(i, len(self._chunks)):
            if self._chunks[j].end_ns <= ns:
                continue
            for fns, fr in self._chunk_frames(j):
                if fns > ns:
                    return self.rel(fns), fr
        return None

    def frame_before(self, rel: float) -> tuple[float, Frame] | None:
        """The last frame strictly before recording time ``rel`` s, or None at the start."""
        return None if rel <= 0 or self._first is None else self.frame_at(rel - 1e-9)

    def _messages(self, topic: str, start: float | None, end: float | None) -> Iterator[tuple[int, bytes]]:
        lo = None if start is None else self._ns(start)
        hi = None if end is None else self._ns(end)
        for i, ref in enumerate(self._chunks):
            if hi is not None and ref.start_ns >= hi or lo is not None and ref.end_ns < lo:
                continue
            for ns, data in self._chunk_messages(i).get(topic, []):
                if (lo is None or ns >= lo) and (hi is None or ns < hi):
                    yield ns, data

    def frames(self, start: float | None = None, end: float | None = None) -> Iterator[tuple[float, Frame]]:
        """``(recording time s, Frame)`` for every readable frame in [start, end) s, in order."""
        lo = None if start is None else self._ns(start)
        hi = None if end is None else self._ns(end)
        for i, ref in enumerate(self._chunks):
            if hi is not None and self._starts[i] >= hi:
                break  # frames are in file order: none of the later chunks has a frame before hi
            if lo is not None and ref.end_ns < lo:
                continue
            for ns, fr in self._chunk_frames(i):
                if (lo is None or ns >= lo) and (hi is None or ns < hi):
                    yield self.rel(ns), fr

    def datagrams(self, start: float | None = None, end: float | None = None) -> Iterator[RecordedDatagram]:
        """Every readable recorded datagram in [start, end) s, in receive order."""
        for ns, data in self._messages(TOPIC_DATAGRAM, start, end):
            try:
                yield decode_datagram(data)
            except (ValueError, KeyError, TypeError) as exc:
                self.warnings.append(f"undecodable datagram at log time {ns} skipped: {exc}")

    def events(self, start: float | None = None, end: float | None = None) -> Iterator[RecordedEvent]:
        """Every readable event in [start, end) s."""
        for ns, data in self._messages(TOPIC_EVENT, start, end):
            try:
                yield decode_event(data, self.rel(ns))
            except (ValueError, KeyError, TypeError):
                continue

    def operator_events(self) -> Iterator[Any]:
        """Every readable operator action (``operator_events.Stamped``), in order; none in files from before
        them (``config.operator_events`` says whether the file has them). Unreadable ones are skipped with a warning."""
        from swarmdeck.console.runtime.operator_events import event_from_dict

        for ns, data in self._messages(TOPIC_OPERATOR, None, None):
            try:
                yield event_from_dict(json.loads(data))
            except ValueError as exc:
                self.warnings.append(f"undecodable operator event at log time {ns} skipped: {exc}")

    def camera_pictures(self, start: float | None = None, end: float | None = None) -> Iterator[tuple[float, bytes]]:
        """``(recording time s, JPEG bytes)`` of the overhead camera pictures in [start, end) s (the Foxglove
        camera channel; none when no camera ran or the file predates it). Undecodable ones are skipped."""
        from swarmdeck.console.recording.foxglove import TOPIC_CAMERA, decode_compressed_image

        for ns, data in self._messages(TOPIC_CAMERA, start, end):
            try:
                _, image = decode_compressed_image(data)
            except ValueError:
                continue
            if image:
                yield self.rel(ns), image

    def config(self) -> dict[str, Any]:
        """The run's configuration message (falls back to the metadata record)."""
        for _, data in self._messages(TOPIC_CONFIG, None, None):
            try:
                return decode_config(data)
            except ValueError:
                break
        return dict(self.metadata)

    def message_counts(self) -> dict[str, int]:
        """Messages per topic: from the MCAP statistics of a cleanly closed file, else by
        reading every chunk (damaged chunks count as empty)."""
        if self._counts is None:
            counts: dict[str, int] = {}
            for i in range(len(self._chunks)):
                for topic, msgs in self._chunk_messages(i).items():
                    counts[topic] = counts.get(topic, 0) + len(msgs)
            self._counts = counts
        return dict(self._counts)

    def count_frames(self) -> int:
        """Number of frames in the file (see :meth:`message_counts`)."""
        return self.message_counts().get(TOPIC_FRAME, 0)

    def close(self) -> None:
        self._f.close()

    def __enter__(self) -> Recording:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def open_recording(path: str | os.PathLike[str]) -> Recording:
    """Open a swarmdeck recording; :class:`RecordingError` with a clear reason if it cannot be played."""
    p = Path(path)
    if p.is_dir():
        raise RecordingError(f"{p} is a folder, not a recording (try `swarmdeck sessions {p}`)")
    if not p.exists():
        raise RecordingError(f"{p}: no such file")
    return Recording(p)
