"""Recovering a recording that was not closed cleanly into a valid, indexed MCAP file.

A console that is killed (``kill -9``, a power cut) leaves an MCAP file with
its data section cut off somewhere and no summary: swarmdeck's own reader
plays it (it scans), and the ``mcap`` package's ``NonSeekingReader`` reads it
with ``log_time_order=False`` up to the cut (REFERENCE.md §13), but
``make_reader`` — and so most tools — cannot open it. :func:`recover` walks
the damaged file with the walk swarmdeck's reader uses
(:mod:`~swarmdeck.console.recording.mcap_walk`: so the recovered file holds exactly
what ``swarmdeck play`` plays of the damaged one) and writes every complete record
into a new file through the ``mcap`` package's ``Writer``, which adds the summary,
the chunk and message indexes and the statistics:

* the header's profile and library, every metadata record and attachment,
  every schema and channel and every message of every complete chunk, in file
  order, one output chunk per input chunk (so seeking stays as cheap as in
  the original);
* a chunk that fails its CRC or cannot be decompressed is skipped and counted
  (the next one is read); messages whose channel record was lost with such a
  chunk are skipped and counted; so is any other record that cannot be parsed;
* reading stops at the first record that runs past the end of the file (the
  crash point) or whose head is damaged (an opcode that is no MCAP record), or
  at the end of the data section of a file that was closed cleanly; a file that
  still has its summary resumes at the next chunk the summary indexes (the
  chunks passed over count as skipped).

The input is only ever read. The output is written to a temporary file beside
it and renamed into place when complete, so an interrupted recovery leaves no
half-written output. Files that are not MCAP, are empty or end inside the
MCAP header raise :class:`RecoveryError` (nothing to recover).
"""
from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from swarmdeck.console.recording.mcap_walk import MAGIC, OP_CHUNK, OP_HEADER, DamagedChunk, McapFile, Stop, parse_record
from swarmdeck.core.errors import SwarmdeckError


class RecoveryError(SwarmdeckError):
    """The input cannot be recovered (not MCAP, empty, cut inside the header) or the output cannot be written."""


@dataclass(frozen=True)
class RecoveryReport:
    """What :func:`recover` did.

    messages: messages written; chunks: chunks read intact; skipped_chunks: chunks dropped (CRC or
    decompression failure, or passed over after a damaged record); orphan_messages: messages dropped
    because their channel record was lost; closed_cleanly: the input already had its data-end record
    (nothing was cut off); stopped: why reading ended (one line); stopped_at: byte offset where it
    ended; skipped_records: other records that could not be parsed.
    """

    source: str
    output: str
    messages: int
    chunks: int
    skipped_chunks: int
    orphan_messages: int
    closed_cleanly: bool
    stopped: str
    stopped_at: int
    skipped_records: int = 0

    def summary(self) -> str:
        """One line for the operator."""
        parts = [f"{self.messages} messages in {self.chunks} chunks"]
        if self.skipped_chunks:
            parts.append(f"{self.skipped_chunks} damaged chunks skipped")
        if self.orphan_messages:
            parts.append(f"{self.orphan_messages} messages without a channel skipped")
        if self.skipped_records:
            parts.append(f"{self.skipped_records} damaged records skipped")
        return f"recovered {self.source} -> {self.output}: {', '.join(parts)}; {self.stopped}"


def default_output(source: str | os.PathLike[str]) -> Path:
    """``<name>.recovered.mcap`` beside ``source``."""
    p = Path(source)
    stem = p.name[:-5] if p.name.endswith(".mcap") else p.name
    return p.with_name(f"{stem}.recovered.mcap")


def _check_head(path: Path) -> int:
    """Size of ``path`` after checking it starts with the MCAP magic and a complete header record."""
    try:
        size = path.stat().st_size
        with open(path, "rb") as f:
            head = f.read(17)
    except OSError as exc:
        raise RecoveryError(f"cannot read {path}: {exc.strerror or exc}") from None
    if size == 0:
        raise RecoveryError(f"{path} is empty: nothing to recover")
    if head[:len(MAGIC)] != MAGIC[:len(head)]:
        raise RecoveryError(f"{path} is not an MCAP file (it does not start with the MCAP magic bytes)")
    if len(head) < len(MAGIC):
        raise RecoveryError(f"{path} is cut off inside the MCAP magic ({size} bytes): nothing to recover")
    if len(head) < 17 or head[8] != 0x01:
        raise RecoveryError(f"{path} is cut off inside the MCAP header ({size} bytes): nothing to recover")
    length = int.from_bytes(head[9:17], "little")
    if 17 + length > size:
        raise RecoveryError(f"{path} is cut off inside the MCAP header ({size} bytes): nothing to recover")
    return size


def _compression_of(name: str) -> Any:
    from mcap.writer import CompressionType

    from swarmdeck.console.recording.recorder import _compression

    return _compression(name) if name in ("zstd", "lz4") else CompressionType.NONE


class _Copier:
    """Re-registers schemas and channels (ids renumbered by the writer) and copies records."""

    def __init__(self, writer: Any) -> None:
        self.w = writer
        self.schemas: dict[int, int] = {0: 0}
        self.channels: dict[int, int] = {}
        self.messages = 0
        self.orphans = 0

    def record(self, rec: Any) -> None:
        from mcap.records import Attachment, Channel, Message, Metadata, Schema

        if isinstance(rec, Message):
            cid = self.channels.get(rec.channel_id)
            if cid is None:
                self.orphans += 1
                return
            self.w.add_message(cid, log_time=rec.log_time, data=rec.data, publish_time=rec.publish_time,
                               sequence=rec.sequence)
            self.messages += 1
        elif isinstance(rec, Schema):
            if rec.id not in self.schemas:
                self.schemas[rec.id] = self.w.register_schema(name=rec.name, encoding=rec.encoding, data=rec.data)
        elif isinstance(rec, Channel):
            if rec.id not in self.channels and rec.schema_id in self.schemas:
                self.channels[rec.id] = self.w.register_channel(
                    topic=rec.topic, message_encoding=rec.message_encoding,
                    schema_id=self.schemas[rec.schema_id], metadata=dict(rec.metadata))
        elif isinstance(rec, Metadata):
            self.w.add_metadata(rec.name, dict(rec.metadata))
        elif isinstance(rec, Attachment):
            self.w.add_attachment(create_time=rec.create_time, log_time=rec.log_time, name=rec.name,
                                  media_type=rec.media_type, data=rec.data)


def _stopped(stop: Stop) -> tuple[bool, str]:
    """(closed cleanly, one line) for where the walk over the input ended."""
    at = f"stopped at byte {stop.offset}"
    if stop.reason == "data_end":
        return True, "the input was closed cleanly (its data section was complete)"
    if stop.reason == "end":
        return False, f"{at}: the file ends there without its summary (the recording was cut off there)"
    if stop.reason == "cut":
        return False, f"{at}: the file ends inside a record (the recording was cut off there)"
    return False, (f"{at}: damaged record (opcode {stop.op:#04x} is no MCAP record; the recording is unreadable "
                   "from there on)")


def recover(source: str | os.PathLike[str], output: str | os.PathLike[str] | None = None) -> RecoveryReport:
    """Write the readable part of MCAP file ``source`` to ``output`` (default :func:`default_output`) as a
    valid MCAP file with summary and indexes. ``source`` is never modified.

    Raises RecoveryError for an input with nothing to recover or an output that cannot be written.
    """
    from mcap.records import Header
    from mcap.writer import Writer

    src = Path(source)
    dst = Path(output) if output is not None else default_output(src)
    size = _check_head(src)
    if dst.exists() and dst.resolve() == src.resolve():
        raise RecoveryError(f"the output must not be the input ({src}): recover never overwrites a recording")
    dst.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp_name = tempfile.mkstemp(prefix=f".{dst.name}.", suffix=".part", dir=dst.parent)
    tmp = Path(tmp_name)
    try:
        with open(src, "rb") as f, os.fdopen(fd, "wb") as out:
            mf = McapFile(f, size)
            head = mf.head(len(MAGIC))
            header = parse_record(OP_HEADER, mf.body(head)) if head is not None and head.op == OP_HEADER else None
            if head is None or not isinstance(header, Header):  # pragma: no cover - _check_head saw a complete header record
                raise RecoveryError(f"{src} does not start with an MCAP header record")
            writer: Any = None
            copier: _Copier | None = None
            chunks = skipped = bad_records = 0

            def start(compression: str) -> _Copier:
                nonlocal writer
                writer = Writer(out, chunk_size=1 << 40, compression=_compression_of(compression))
                writer.start(profile=header.profile, library=header.library)
                return _Copier(writer)

            summary, _ = mf.summary()
            indexed = [c.offset for c in summary.chunks] if summary is not None else []
            walk = mf.walk(head.end, resume=indexed)
            pending: list[Any] = []  # records before the first chunk (its compression picks the output's)
            for rec in walk:
                if rec.op == OP_CHUNK:
                    try:
                        chunk, inner = mf.read_chunk(rec)
                    except DamagedChunk:  # CRC mismatch, corrupt compression, cut inner record
                        skipped += 1
                        continue
                    if copier is None:
                        copier = start(chunk.compression)
                        for p in pending:
                            copier.record(p)
                    for r in inner:
                        copier.record(r)
                    writer.flush()  # one output chunk per input chunk
                    chunks += 1
                    continue
                try:
                    parsed = parse_record(rec.op, mf.body(rec))
                except Exception:  # noqa: BLE001 - struct/unicode/mcap errors in a damaged record body
                    bad_records += 1
                    continue
                if parsed is None:
                    continue
                if copier is None:
                    pending.append(parsed)
                else:
                    copier.record(parsed)
            skipped += sum(1 for lo, hi in walk.skipped for c in indexed if lo <= c < hi)
            assert walk.stop is not None
            clean, stopped = _stopped(walk.stop)
            if copier is None:
                copier = start("zstd")
                for p in pending:
                    copier.record(p)
            writer.finish()
            out.flush()
            os.fsync(out.fileno())
            at = walk.stop.offset
        os.chmod(tmp, 0o644)
        os.replace(tmp, dst)
    except RecoveryError:
        tmp.unlink(missing_ok=True)
        raise
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise RecoveryError(f"cannot write {dst}: {exc.strerror or exc}") from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return RecoveryReport(str(src), str(dst), copier.messages, chunks, skipped, copier.orphans, clean, stopped, at,
                          bad_records)
