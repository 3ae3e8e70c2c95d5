"""One damage-tolerant walk over an MCAP file: what the reader plays and what ``recover`` writes.

The reader (:mod:`~swarmdeck.console.recording.reader`) and ``recover``
(:mod:`~swarmdeck.console.recording.recover`) both see a file through :class:`McapFile`, so a
damaged recording plays exactly what its recovered copy holds (REFERENCE.md §10 for the MCAP
records, §13 for the crash behaviour):

* a record *head* (opcode u8, length u64) is damaged when its opcode is no MCAP record (0, or above
  0x0F: zeroed or overwritten bytes) — the walk ends there ("damaged") — or when its length runs
  past the end of the file — the walk ends there ("cut": the recording was cut off inside it); a
  file that ends between two records ends the walk "end" (cut off with no summary), a data-end or
  footer record "data_end" (the data section was complete);
* when the walk ends early and the file's summary (:meth:`McapFile.summary`) indexes a chunk
  further on, the walk resumes at that chunk (the damaged span is listed in :attr:`Walk.skipped`);
* a chunk is read with its CRC checked (:meth:`McapFile.read_chunk`); one that fails its CRC,
  cannot be decompressed or holds a cut record raises :class:`DamagedChunk` — both callers skip it
  and read the next one.

Nothing here writes; the file object is only read (and seeked).
"""
from __future__ import annotations

import io
import struct
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any, BinaryIO, Literal

from swarmdeck.core.errors import SwarmdeckError

MAGIC = bytes([137, 77, 67, 65, 80, 48, 13, 10])
OP_HEADER, OP_FOOTER, OP_SCHEMA, OP_CHANNEL, OP_MESSAGE, OP_CHUNK = 0x01, 0x02, 0x03, 0x04, 0x05, 0x06
OP_MESSAGE_INDEX, OP_CHUNK_INDEX, OP_ATTACHMENT, OP_ATTACHMENT_INDEX = 0x07, 0x08, 0x09, 0x0A
OP_STATISTICS, OP_METADATA, OP_METADATA_INDEX, OP_SUMMARY_OFFSET, OP_DATA_END = 0x0B, 0x0C, 0x0D, 0x0E, 0x0F
MAX_OPCODE = 0x0F
HEAD = struct.Struct("<BQ")  # opcode, body length: every record starts with these 9 bytes
#: Bytes of a footer record and the closing magic at the end of a cleanly closed file.
FOOTER_SIZE = 9 + 20 + len(MAGIC)

StopReason = Literal["end", "cut", "damaged", "data_end"]


class DamagedChunk(ValueError, SwarmdeckError):
    """A chunk record that cannot be read: a bad CRC, undecodable compression, a cut record inside."""


@dataclass(frozen=True)
class Record:
    """Where one record is: ``op`` its opcode, ``offset`` of its opcode byte, ``length`` of its body (bytes)."""

    op: int
    offset: int
    length: int

    @property
    def body_offset(self) -> int:
        return self.offset + HEAD.size

    @property
    def end(self) -> int:
        """Offset of the byte after the record."""
        return self.offset + HEAD.size + self.length


@dataclass(frozen=True)
class Stop:
    """Why a walk ended: ``reason`` (module docstring) at byte ``offset``; ``op``: the damaged or cut
    record's opcode (None when the file ended between records)."""

    reason: StopReason
    offset: int
    op: int | None = None


@dataclass(frozen=True)
class ChunkRef:
    """Where one chunk is: ``offset`` of its record (opcode byte), message time range (ns)."""

    offset: int
    start_ns: int
    end_ns: int


@dataclass(frozen=True)
class Summary:
    """What a cleanly closed file's summary section says: its chunks (in file order), channel id →
    topic, and messages per channel id (None without a statistics record)."""

    chunks: tuple[ChunkRef, ...]
    channels: dict[int, str]
    channel_counts: dict[int, int] | None


@dataclass
class Walk:
    """The records of a data section in file order (iterate once). After the iteration, :attr:`stop`
    says why it ended and :attr:`skipped` lists the (from, to) byte spans passed over to resume at a
    chunk the summary indexes."""

    file: McapFile
    start: int
    resume: Sequence[int] = ()
    stop: Stop | None = None
    skipped: list[tuple[int, int]] = field(default_factory=list)

    def __iter__(self) -> Iterator[Record]:
        pos = self.start
        later = sorted(self.resume)
        while True:
            rec = self.file.head(pos)
            if rec is None or rec.op in (OP_DATA_END, OP_FOOTER):
                stop = Stop("data_end", pos, rec.op) if rec is not None else self.file.why_not(pos)
                nxt = next((r for r in later if r > pos), None)
                if stop.reason == "data_end" or nxt is None:
                    self.stop = stop
                    return
                self.skipped.append((pos, nxt))
                pos = nxt
                continue
            yield rec
            pos = rec.end


class McapFile:
    """An MCAP file open for reading: ``f`` a binary file object of ``size`` bytes (module docstring)."""

    def __init__(self, f: BinaryIO, size: int) -> None:
        self.f = f
        self.size = size

    def read(self, pos: int, n: int) -> bytes:
        """Up to ``n`` bytes at ``pos``."""
        self.f.seek(pos)
        return self.f.read(n)

    def head(self, pos: int) -> Record | None:
        """The record at ``pos``, or None when its head is damaged or it runs past the end of the file
        (:meth:`why_not` tells which)."""
        if pos + HEAD.size > self.size:
            return None
        raw = self.read(pos, HEAD.size)
        if len(raw) < HEAD.size:
            return None
        op, length = HEAD.unpack(raw)
        if op == 0 or op > MAX_OPCODE or pos + HEAD.size + length > self.size:
            return None
        return Record(op, pos, length)

    def why_not(self, pos: int) -> Stop:
        """Why there is no readable record at ``pos``: the file ends there ("end"), is cut inside a
        record ("cut"), or the record's head is damaged ("damaged")."""
        if pos >= self.size:
            return Stop("end", pos)
        raw = self.read(pos, HEAD.size)
        if len(raw) < HEAD.size:
            return Stop("cut", pos, raw[0] if raw else None)
        op, _ = HEAD.unpack(raw)
        return Stop("cut" if 0 < op <= MAX_OPCODE else "damaged", pos, op)

    def body(self, rec: Record) -> bytes:
        """The body of ``rec`` (ValueError if the file changed under us and it is short)."""
        data = self.read(rec.body_offset, rec.length)
        if len(data) < rec.length:
            raise ValueError(f"record at byte {rec.offset} is cut off")
        return data

    def walk(self, start: int, resume: Sequence[int] = ()) -> Walk:
        """The records from byte ``start`` on (:class:`Walk`); ``resume``: offsets of indexed chunks to
        go on at after damage (the summary's, when the file has one)."""
        return Walk(self, start, resume)

    def read_chunk(self, at: Record | int) -> tuple[Any, list[Any]]:
        """(the ``mcap.records.Chunk``, its schema, channel and message records) of the chunk record
        ``at`` (a record or its offset), CRC checked; :class:`DamagedChunk` naming the cause otherwise."""
        from mcap.stream_reader import breakup_chunk

        rec = at if isinstance(at, Record) else self.head(at)
        if rec is None or rec.op != OP_CHUNK:
            raise DamagedChunk("not a chunk record")
        try:
            chunk = parse_record(rec.op, self.body(rec))
            return chunk, breakup_chunk(chunk, validate_crc=True)
        except Exception as exc:  # noqa: BLE001 - damage of any kind (CRC, zstd, struct, cut record)
            raise DamagedChunk(type(exc).__name__) from exc

    def summary(self) -> tuple[Summary | None, str | None]:
        """The summary section of a cleanly closed file, read with ``struct`` (12 000 chunk indexes in
        a few ms), and a warning: (None, None) without a footer, (None, reason) when the summary is
        missing, unreadable or points outside the data."""
        from mcap.data_stream import ReadDataStream
        from mcap.records import Statistics

        footer_at = self.size - FOOTER_SIZE  # Footer: opcode, length 20, summary_start, summary_offset_start, crc
        if footer_at < len(MAGIC):
            return None, None
        tail = self.read(footer_at, FOOTER_SIZE)
        if len(tail) != FOOTER_SIZE or tail[29:] != MAGIC or HEAD.unpack_from(tail)[:2] != (OP_FOOTER, 20):
            return None, None
        summary_start = struct.unpack_from("<Q", tail, 9)[0]
        if not len(MAGIC) <= summary_start < footer_at:
            return None, None
        buf = self.read(summary_start, footer_at - summary_start)
        chunks: list[ChunkRef] = []
        channels: dict[int, str] = {}
        counts: dict[int, int] | None = None
        chunk_count: int | None = None
        p = 0
        try:
            while p + HEAD.size <= len(buf):
                op, length = HEAD.unpack_from(buf, p)
                body, end = p + HEAD.size, p + HEAD.size + length
                if end > len(buf):
                    return None, None
                if op == OP_CHUNK_INDEX:
                    start_ns, end_ns, offset = struct.unpack_from("<QQQ", buf, body)
                    chunks.append(ChunkRef(offset, start_ns, end_ns))
                elif op == OP_CHANNEL:
                    cid, topic = channel_topic(buf[body:end])
                    channels[cid] = topic
                elif op == OP_STATISTICS:
                    stats = Statistics.read(ReadDataStream(io.BytesIO(buf[body:end])))
                    counts = {int(k): int(v) for k, v in stats.channel_message_counts.items()}
                    chunk_count = int(stats.chunk_count)
                p = end
        except (struct.error, ValueError, UnicodeDecodeError):
            return None, None
        if not chunks and chunk_count != 0:  # no index although the file has chunks (or says nothing)
            return None, None
        if any(c.offset < len(MAGIC) or c.offset >= summary_start for c in chunks):
            return None, "the MCAP summary points outside the data; scanned the file instead"
        return Summary(tuple(sorted(chunks, key=lambda c: c.offset)), channels, counts), None


def channel_topic(body: bytes) -> tuple[int, str]:
    """(id, topic) of a Channel record body: id u16, schema_id u16, topic (u32 length + UTF-8), …"""
    cid, _schema, n = struct.unpack_from("<HHI", body, 0)
    if 8 + n > len(body):
        raise ValueError("channel topic runs past the record")
    return cid, body[8:8 + n].decode("utf-8")


def parse_record(op: int, body: bytes) -> Any:
    """The ``mcap.records`` object of a record body with opcode ``op`` (None for an opcode without one);
    the mcap package's errors (struct, Unicode, its own) for a damaged body."""
    from mcap import records as r
    from mcap.data_stream import ReadDataStream

    readers: dict[int, Callable[[ReadDataStream], Any]] = {
        OP_HEADER: r.Header.read, OP_FOOTER: r.Footer.read, OP_SCHEMA: r.Schema.read, OP_CHANNEL: r.Channel.read,
        OP_CHUNK: r.Chunk.read, OP_MESSAGE_INDEX: r.MessageIndex.read, OP_CHUNK_INDEX: r.ChunkIndex.read,
        OP_ATTACHMENT: r.Attachment.read, OP_ATTACHMENT_INDEX: r.AttachmentIndex.read,
        OP_STATISTICS: r.Statistics.read, OP_METADATA: r.Metadata.read, OP_METADATA_INDEX: r.MetadataIndex.read,
        OP_SUMMARY_OFFSET: r.SummaryOffset.read, OP_DATA_END: r.DataEnd.read}
    stream = ReadDataStream(io.BytesIO(body))
    if op == OP_MESSAGE:
        return r.Message.read(stream, len(body))
    read = readers.get(op)
    return None if read is None else read(stream)


__all__ = ["MAGIC", "MAX_OPCODE", "ChunkRef", "DamagedChunk", "McapFile", "Record", "Stop", "Summary", "Walk",
           "channel_topic", "parse_record"]
