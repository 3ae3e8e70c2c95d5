"""Recovering a recording that was not closed cleanly into a valid, indexed MCAP file.

A console that is killed (``kill -9``, a power cut) leaves an MCAP file with
its data section cut off somewhere and no summary: swarmdeck's own reader
plays it (it scans), and the ``mcap`` package's ``NonSeekingReader`` reads it
with ``log_time_order=False`` up to the cut (REFERENCE.md §13), but
``make_reader`` — and so most tools — cannot open it. :func:`recover` reads
the damaged file with the ``mcap`` package's own :class:`~mcap.stream_reader.StreamReader`
and writes every complete record into a new file through the ``mcap``
package's ``Writer``, which adds the summary, the chunk and message indexes
and the statistics:

* the header's profile and library, every metadata record and attachment,
  every schema and channel and every message of every complete chunk, in file
  order, one output chunk per input chunk (so seeking stays as cheap as in
  the original);
* a chunk that fails its CRC or cannot be decompressed is skipped and counted
  (the next one is read); messages whose channel record was lost with such a
  chunk are skipped and counted;
* reading stops at the first record that runs past the end of the file or
  cannot be parsed (the crash point), or at the end of the data section of a
  file that was closed cleanly.

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

from swarmdeck.core.errors import SwarmdeckError

MAGIC = bytes([137, 77, 67, 65, 80, 48, 13, 10])


class RecoveryError(SwarmdeckError):
    """The input cannot be recovered (not MCAP, empty, cut inside the header) or the output cannot be written."""


@dataclass(frozen=True)
class RecoveryReport:
    """What :func:`recover` did.

    messages: messages written; chunks: chunks read intact; skipped_chunks: chunks dropped (CRC or
    decompression failure); orphan_messages: messages dropped because their channel record was lost;
    closed_cleanly: the input already had its data-end record (nothing was cut off);
    stopped: why reading ended (one line); stopped_at: byte offset where it ended.
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

    def summary(self) -> str:
        """One line for the operator."""
        parts = [f"{self.messages} messages in {self.chunks} chunks"]
        if self.skipped_chunks:
            parts.append(f"{self.skipped_chunks} damaged chunks skipped")
        if self.orphan_messages:
            parts.append(f"{self.orphan_messages} messages without a channel skipped")
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


def recover(source: str | os.PathLike[str], output: str | os.PathLike[str] | None = None) -> RecoveryReport:
    """Write the readable part of MCAP file ``source`` to ``output`` (default :func:`default_output`) as a
    valid MCAP file with summary and indexes. ``source`` is never modified.

    Raises RecoveryError for an input with nothing to recover or an output that cannot be written.
    """
    from mcap.exceptions import McapError
    from mcap.records import Chunk, DataEnd, Footer, Header
    from mcap.stream_reader import StreamReader, breakup_chunk
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
            reader = StreamReader(f, emit_chunks=True, record_size_limit=size)
            records = reader.records
            header = next(records)
            if not isinstance(header, Header):  # pragma: no cover - _check_head saw opcode 0x01
                raise RecoveryError(f"{src} does not start with an MCAP header record")
            writer: Any = None
            copier: _Copier | None = None
            chunks = skipped = 0
            clean = False
            stopped = "the file ends cleanly"

            def start(compression: str) -> _Copier:
                nonlocal writer
                writer = Writer(out, chunk_size=1 << 40, compression=_compression_of(compression))
                writer.start(profile=header.profile, library=header.library)
                return _Copier(writer)

            pending: list[Any] = []  # records before the first chunk (its compression picks the output's)
            try:
                for rec in records:
                    if isinstance(rec, Chunk):
                        try:
                            inner = breakup_chunk(rec, validate_crc=True)
                        except Exception:  # noqa: BLE001 - CRC mismatch, corrupt compression, cut inner record
                            skipped += 1
                            continue
                        if copier is None:
                            copier = start(rec.compression)
                            for p in pending:
                                copier.record(p)
                        for r in inner:
                            copier.record(r)
                        writer.flush()  # one output chunk per input chunk
                        chunks += 1
                    elif isinstance(rec, (DataEnd, Footer)):
                        clean, stopped = True, "the input was closed cleanly (its data section was complete)"
                        break
                    elif copier is None:
                        pending.append(rec)
                    else:
                        copier.record(rec)
            except McapError as exc:
                what = "the file ends inside a record" if "EndOfFile" in type(exc).__name__ else f"damaged record ({exc})"
                stopped = f"stopped at byte {f.tell()}: {what} (the recording was cut off there)"
            except Exception as exc:  # noqa: BLE001 - struct/unicode errors in a damaged record body
                stopped = f"stopped at byte {f.tell()}: unreadable record ({type(exc).__name__}: {exc})"
            if copier is None:
                copier = start("zstd")
                for p in pending:
                    copier.record(p)
            writer.finish()
            out.flush()
            os.fsync(out.fileno())
            at = f.tell()
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
    return RecoveryReport(str(src), str(dst), copier.messages, chunks, skipped, copier.orphans, clean, stopped, at)
