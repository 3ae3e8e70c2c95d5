"""The session recorder: Frames, raw input datagrams and events into an MCAP file.

The loop thread only *enqueues* (an append under a lock, a few µs); a
background writer thread serialises (:func:`~swarmdeck.console.recording.codec.encode_frame`:
compact JSON with binary per-robot arrays, frame format 3) and writes
chunked, zstd-compressed MCAP (format in
:mod:`swarmdeck.console.recording.schemas`). It closes the current chunk after
``chunk_frames`` frames (counted, never timed: a slow live console writes the same keyframe
cadence as a fast one), before it grows past ``chunk_size`` bytes, and when no item has arrived
for ``flush_interval`` s of wall time (a paused loop): a crash or ``kill -9`` loses at
most about that much (what was written sits in the OS page cache, which survives the
process), and a seek decodes at most that much data, even in files written faster than
real time. The first frame of every chunk is a self-contained keyframe and the others are
predicted from the frame before them in the same chunk (codec.py), so every chunk decodes on
its own.

The queue is bounded: when the disk cannot keep up, the *oldest* queued items
are dropped and counted (``status().dropped``, and a recorder event in the
file). An unwritable path or a full disk never raises into the loop: the
recorder turns itself off, ``status().message`` says why, and the run goes on.

Wiring in the console (``--record PATH`` / ``--no-record``)::

    from swarmdeck.console.recording.recorder import Recorder, default_path
    from swarmdeck.console.recording.resimulate import session_metadata

    rec = Recorder(args.record or default_path(),            # sessions/<UTC timestamp>.mcap
                   session_metadata(loop_config, inputs_table))  # what re-simulation needs
    hub = InputHub.from_config(input_config, clock=clock, on_datagram=rec.raw_datagram)
    rec.follow(loop)       # its Frames and typed operator actions (enqueue only, on the loop thread)
    rec.write_event(t, "note", "…")                          # optional: free-text notices
    st = rec.status()                                        # show st.message when not st.ok
    rec.close()                                              # at exit: finishes the index
"""
from __future__ import annotations

import datetime as _dt
import os
import platform
import threading
import time
from collections import deque
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, BinaryIO

from swarmdeck.console.recording.codec import (
    CODEC_FORMAT,
    datagram_message,
    encode_frame,
    encode_json,
    event_message,
    metadata_record,
)
from swarmdeck.console.recording.foxglove import TOPIC_LOG, FoxgloveConfig, FoxgloveEncoder, channel_specs
from swarmdeck.console.recording.schemas import (
    CHANNELS,
    METADATA_NAME,
    OPERATOR_EVENTS,
    PROFILE,
    RECORDING_FORMAT,
    TOPIC_CONFIG,
    TOPIC_DATAGRAM,
    TOPIC_EVENT,
    TOPIC_FRAME,
    TOPIC_OPERATOR,
)
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.core.bounds import DEFAULT_BOUNDS
from swarmdeck.core.checks import require_in_range
from swarmdeck.core.service_thread import ServiceThread

DEFAULT_DIR = "sessions"


@dataclass(frozen=True)
class RecorderConfig:
    """Recorder tuning.

    queue_size: items (frames + datagrams + events) waiting for the writer; beyond it the oldest are dropped.
    chunk_frames: frames per chunk: a chunk is closed after this many frames (20 ≈ 0.67 s at 30 Hz), so
        every chunk starts with a keyframe at the same cadence in frames however fast the loop or the
        disk runs (a slow live console writes the same file as a fast one). Keyframes are what a
        recording of many robots mostly pays for: 8 (the default before issue 27) is ≈ 10 % larger at
        N = 1000 (bench/RESULTS.md, "recording size"); smaller seeks and recovers in finer steps.
    flush_interval: wall s; a chunk holding data is also closed when no item has arrived for this
        long (a paused loop, datagrams only) — with ``chunk_frames`` it bounds the data lost on a crash.
    chunk_size: bytes; a chunk is also closed when it reaches this (after the item that got it there).
    compression: "zstd", "lz4" or "none" (falls back to what is importable).
    foxglove: also write Foxglove's native channels (``recording/foxglove.py``: scene, poses, density,
        camera, transforms, log, metrics), so Foxglove's panels draw the run without an extension.
    """

    queue_size: int = 4096
    chunk_frames: int = 20
    flush_interval: float = 0.25
    chunk_size: int = 4 * 1024 * 1024
    compression: str = "zstd"
    foxglove: bool = True

    def __post_init__(self) -> None:
        require_in_range(self.queue_size, "queue_size", 1, integer=True)
        require_in_range(self.chunk_frames, "chunk_frames", 1, integer=True)
        require_in_range(self.flush_interval, "flush_interval", 0.0, unit="s", lo_open=True)
        if self.compression not in ("zstd", "lz4", "none"):
            raise ValueError(f"compression must be 'zstd', 'lz4' or 'none', got {self.compression!r}")


@dataclass(frozen=True)
class RecorderStatus:
    """What the recorder is doing. ``state``: "recording" | "disabled" (never started) | "failed"
    (stopped on a write error) | "closed". ``message`` is a one-line explanation for the operator."""

    path: str
    state: str
    message: str
    frames: int
    datagrams: int
    events: int
    dropped: int
    queued: int
    bytes_written: int

    @property
    def ok(self) -> bool:
        """True while recording (or after a clean close)."""
        return self.state in ("recording", "closed")


def default_path(directory: str | os.PathLike[str] = DEFAULT_DIR, now: float | None = None) -> Path:
    """``<directory>/<UTC timestamp>.mcap``, e.g. ``sessions/20261121-223012.mcap`` (suffixed if taken)."""
    stamp = _dt.datetime.fromtimestamp(time.time() if now is None else now, _dt.UTC)
    base = Path(directory) / stamp.strftime("%Y%m%d-%H%M%S")
    path = base.with_suffix(".mcap")
    k = 1
    while path.exists():
        path = Path(f"{base}-{k}.mcap")
        k += 1
    return path


def software_versions() -> dict[str, str]:
    """Versions of swarmdeck and the libraries that shape a recording."""
    from importlib.metadata import PackageNotFoundError, version

    out = {"python": platform.python_version(), "platform": platform.platform()}
    for pkg in ("swarmdeck", "numpy", "scipy", "mcap", "foxglove-sdk", "viser", "clarabel"):
        try:
            out[pkg] = version(pkg)
        except PackageNotFoundError:
            continue
    return out


def _compression(name: str) -> Any:
    from mcap.writer import CompressionType

    order = {"zstd": ("zstd", "lz4", "none"), "lz4": ("lz4", "none"), "none": ("none",)}[name]
    for cand in order:
        try:
            if cand == "zstd":
                import zstandard  # noqa: F401
                return CompressionType.ZSTD
            if cand == "lz4":
                import lz4.frame  # noqa: F401
                return CompressionType.LZ4
        except ImportError:
            continue
    return CompressionType.NONE


_json = encode_json  # compact strict JSON (msgspec), from the codec


class Recorder:
    """Writes one session to ``path`` (MCAP) from a background thread.

    Args:
        path: output file; parent folders are created. ``None`` → :func:`default_path`.
        metadata: JSON-able run description; recognised keys ``robots`` (ids), ``bounds``
            (x_min, x_max, y_min, y_max m), ``config`` (any JSON object); others are kept.
            ``robots``/``bounds`` default to the first frame's.
        config: :class:`RecorderConfig`.
        wallclock: Unix seconds, for the file's start time (tests pass a fixed clock).
        opener: opens ``path`` for binary writing (default ``open(path, "wb")``; tests pass a
            file that stalls like a slow disk). Needs ``write``, ``flush``, ``tell``, ``close``.
        image_provider: the camera source's ``image(ref)`` for the Foxglove camera channel, if a camera runs.
        foxglove: options of the Foxglove channels (``FoxgloveConfig``).
        capsule: what reproduces the run (``capsule.Manifest.to_dict()``), written as the
            ``swarmdeck.capsule`` metadata record right after the header; ``capsule_files`` (relative path →
            bytes: the script files it names) as MCAP attachments ``capsule/<path>``
            (:mod:`~swarmdeck.console.recording.capsule`; ``swarmdeck capsule`` reads both back).

    Every method is safe to call from any thread and never raises on I/O problems.
    """

    def __init__(self, path: str | os.PathLike[str] | None = None, metadata: Mapping[str, Any] | None = None,
                 config: RecorderConfig | None = None, *, wallclock: Callable[[], float] = time.time,
                 opener: Callable[[Path], BinaryIO] | None = None, image_provider: Callable[[str], Any] | None = None,
                 foxglove: FoxgloveConfig | None = None, capsule: Mapping[str, Any] | None = None,
                 capsule_files: Mapping[str, bytes] | None = None) -> None:
        self.config = config or RecorderConfig()
        self._capsule = None if capsule is None else dict(capsule)
        self._capsule_files = {str(k): bytes(v) for k, v in (capsule_files or {}).items()}
        self.path = Path(default_path() if path is None else path)
        self._meta = dict(metadata or {})
        self._lock = threading.Lock()
        self._queue: deque[tuple[Any, ...]] = deque()
        self._service = ServiceThread(self._run, "swarmdeck-recorder")
        self._counts = {"frames": 0, "datagrams": 0, "events": 0, "dropped": 0}
        self._state = "recording"
        self._message = f"recording to {self.path}"
        self._bytes = 0
        self._start_ns = int(wallclock() * 1e9)
        self._opener = opener or (lambda p: open(p, "wb"))
        self._origin: float | None = None
        self._file: Any = None
        self._writer: Any = None
        self._channels: dict[str, int] = {}
        self._image_provider = image_provider
        self._foxglove_config = foxglove if foxglove is not None else FoxgloveConfig()
        self._foxglove: FoxgloveEncoder | None = None
        self._foxglove_errors = 0
        self._foxglove_error = ""
        self._previous: Frame | None = None  # the frame written last in the open chunk (frames predict from it)
        self._chunk_bytes = 0  # message bytes in the open chunk
        try:
            self._open()
        except Exception as exc:  # noqa: BLE001 - unwritable path, full disk, …: record nothing, run on
            self._fail("disabled", f"recording disabled: cannot write {self.path}: {_reason(exc)}")
            return
        self._service.start()

    # ------------------------------------------------------------------ loop side
    def write_frame(self, frame: Frame) -> bool:
        """Queue one tick's Frame (serialised on the writer thread). False when not recording."""
        return self._put(("f", frame))

    def write_datagram(self, data: bytes, peer: object, transport: str, t: float,
                       listener: str | None = None) -> bool:
        """Queue one raw input datagram received at console time ``t`` (s)."""
        return self._put(("d", bytes(data), peer, str(transport), float(t), listener))

    def raw_datagram(self, data: bytes, peer: object, transport: str, t: float) -> None:
        """The inputs ``on_datagram(data, peer, transport, t)`` hook."""
        self.write_datagram(data, peer, transport, t)

    def datagram_hook(self, listener: str) -> Callable[[bytes, object, str, float], None]:
        """An ``on_datagram`` hook that also records which listener received the datagram."""
        def hook(data: bytes, peer: object, transport: str, t: float) -> None:
            self.write_datagram(data, peer, transport, t, listener)
        return hook

    def write_event(self, t: float, kind: str, text: str) -> bool:
        """Queue an event (operator action, notice) at console time ``t`` (s)."""
        return self._put(("e", float(t), str(kind), str(text)))

    def write_operator(self, events: Any) -> bool:
        """Queue a tick's operator actions (``operator_events.Stamped``; the loop's operator listener)."""
        from swarmdeck.console.runtime.operator_events import event_to_dict

        ok = True
        for e in events:
            ok = self._put(("o", float(e.time), event_to_dict(e))) and ok
        return ok

    def follow(self, loop: Any) -> Callable[[], None]:
        """Record ``loop``: every Frame and every operator action (``config.operator_events``, so
        re-simulation replays the actions). Call before the loop's first tick; returns an unsubscribe."""
        self._meta["config"] = {**dict(self._meta.get("config", {})), "operator_events": OPERATOR_EVENTS}
        frames = loop.subscribe(self.write_frame)
        actions = loop.subscribe_operator(self.write_operator)

        def unsubscribe() -> None:
            frames()
            actions()

        return unsubscribe

    def _put(self, item: tuple[Any, ...]) -> bool:
        if self._state != "recording":
            return False
        with self._lock:
            q = self._queue
            if len(q) >= self.config.queue_size:
                q.popleft()
                self._counts["dropped"] += 1
            q.append(item)
        return True

    def status(self) -> RecorderStatus:
        """A snapshot of the recorder's state and counters."""
        with self._lock:
            c = dict(self._counts)
            queued = len(self._queue)
        msg = self._message
        if self._state == "recording" and c["dropped"]:
            msg = f"{msg} ({c['dropped']} items dropped: disk too slow)"
        return RecorderStatus(str(self.path), self._state, msg, c["frames"], c["datagrams"], c["events"],
                              c["dropped"], queued, self._bytes)

    def close(self, timeout: float = 10.0) -> RecorderStatus:
        """Write what is queued, finish the file (summary + index) and stop the thread. Idempotent."""
        self._service.stop(timeout)
        return self.status()

    def __enter__(self) -> Recorder:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ------------------------------------------------------------------ writer thread
    def _open(self) -> None:
        from mcap.writer import Writer

        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._file = self._opener(self.path)
        # chunks are closed only here (_close_chunk): each must start with a keyframe
        w = Writer(self._file, chunk_size=1 << 62, compression=_compression(self.config.compression))
        swarmdeck_version = software_versions().get("swarmdeck", "0")
        w.start(profile=PROFILE, library=f"swarmdeck {swarmdeck_version}")
        meta = {
            "recording_format": RECORDING_FORMAT,
            "frame_format": CODEC_FORMAT,
            "created": _dt.datetime.fromtimestamp(self._start_ns / 1e9, _dt.UTC).isoformat(),
            "start_unix_ns": self._start_ns,
            "versions": software_versions(),
            **{k: v for k, v in self._meta.items() if k != "config"},
        }
        w.add_metadata(METADATA_NAME, metadata_record(meta))
        self._write_capsule(w)
        for topic, (name, schema) in CHANNELS.items():
            sid = w.register_schema(name=name, encoding="jsonschema", data=_json(schema))
            self._channels[topic] = w.register_channel(topic=topic, message_encoding="json", schema_id=sid)
        if self.config.foxglove:
            for spec in channel_specs(packed=self._foxglove_config.packed):
                sid = w.register_schema(name=spec.schema_name, encoding=spec.schema_encoding, data=spec.schema_data)
                self._channels[spec.topic] = w.register_channel(topic=spec.topic, message_encoding=spec.message_encoding,
                                                                schema_id=sid)
        self._writer = w
        self._file.flush()
        self._bytes = self._file.tell()

    def _write_capsule(self, w: Any) -> None:
        """The capsule's manifest (a metadata record) and its files (attachments), before any message."""
        from swarmdeck.console.recording.capsule import ATTACHMENT_PREFIX, CAPSULE_METADATA_NAME

        if self._capsule is None:
            return
        w.add_metadata(CAPSULE_METADATA_NAME, metadata_record({"manifest": self._capsule}))
        for name in sorted(self._capsule_files):
            w.add_attachment(self._start_ns, self._start_ns, ATTACHMENT_PREFIX + name, "application/octet-stream",
                             self._capsule_files[name])

    def _log_ns(self, t: float) -> int:
        if self._origin is None:
            self._origin = t
        return max(0, self._start_ns + round((t - self._origin) * 1e9))

    def _write_config(self, first_t: float, frame: Frame | None) -> None:
        cfg = {
            "recording_format": RECORDING_FORMAT, "frame_format": CODEC_FORMAT,
            "created": _dt.datetime.fromtimestamp(self._start_ns / 1e9, _dt.UTC).isoformat(),
            "start_unix_ns": self._start_ns, "time_origin": first_t,
            "robots": list(self._meta.get("robots", frame.ids.tolist() if frame is not None else [])),
            "bounds": list(self._meta.get("bounds", frame.bounds if frame is not None else DEFAULT_BOUNDS)),
            "versions": software_versions(),
            "config": dict(self._meta.get("config", {})),
            **{k: v for k, v in self._meta.items() if k not in ("robots", "bounds", "config")},
        }
        self._add(TOPIC_CONFIG, first_t, cfg)

    def _add(self, topic: str, t: float, payload: dict[str, Any] | bytes) -> None:
        ns = self._log_ns(t)
        data = payload if isinstance(payload, bytes) else _json(payload)
        self._writer.add_message(self._channels[topic], log_time=ns, data=data, publish_time=ns)
        self._chunk_bytes += len(data)

    def _close_chunk(self) -> None:
        """Write the open chunk (the next frame is a keyframe: no chunk depends on another)."""
        self._writer.flush()
        self._bytes = self._file.tell()
        self._previous = None
        self._chunk_bytes = 0

    def _write_item(self, item: tuple[Any, ...]) -> None:
        kind = item[0]
        if self._origin is None:
            t0 = item[1].time if kind == "f" else (item[4] if kind == "d" else item[1])  # "e", "o": item[1]
            self._write_config(float(t0), item[1] if kind == "f" else None)
        if kind == "f":
            frame: Frame = item[1]
            self._add(TOPIC_FRAME, frame.time, encode_frame(frame, self._previous))
            self._previous = frame
            for text in frame.events:
                self._add(TOPIC_EVENT, frame.time, event_message(frame.time, "frame", text))
            self._counts["frames"] += 1
            self._write_foxglove(lambda enc, ns: enc.encode(frame, ns, frame.time - self._origin), frame)
        elif kind == "d":
            _, data, peer, transport, t, listener = item
            self._add(TOPIC_DATAGRAM, t, datagram_message(data, peer, transport, t, listener))
            self._counts["datagrams"] += 1
        elif kind == "o":
            _, t, event = item
            self._add(TOPIC_OPERATOR, t, event)
            self._counts["events"] += 1
        else:
            _, t, k, text = item
            self._add(TOPIC_EVENT, t, event_message(t, k, text))
            self._counts["events"] += 1
            self._write_foxglove(lambda enc, ns: [(TOPIC_LOG, ns, enc.log(ns, text, name=k))], None, t)

    def _write_foxglove(self, messages: Callable[[FoxgloveEncoder, int], Any], frame: Frame | None,
                        t: float | None = None) -> None:
        """Write the Foxglove channels' messages; a failure there never costs the Frame (counted, said once)."""
        if not self.config.foxglove:
            return
        try:
            if self._foxglove is None:
                bounds = self._meta.get("bounds", frame.bounds if frame is not None else DEFAULT_BOUNDS)
                self._foxglove = FoxgloveEncoder(tuple(bounds), config=self._foxglove_config,
                                                 image_provider=self._image_provider)
            ns = self._log_ns(frame.time if frame is not None else t)
            for topic, at, data in messages(self._foxglove, ns):
                self._writer.add_message(self._channels[topic], log_time=at, data=data, publish_time=at)
                self._chunk_bytes += len(data)
        except Exception as exc:  # noqa: BLE001 - a drawing-side bug must not stop the recording
            self._foxglove_errors += 1
            if self._foxglove_errors == 1:
                self._foxglove_error = f"Foxglove channels failed: {type(exc).__name__}: {exc}"
                self._message = f"recording to {self.path}; {self._foxglove_error}"

    def _run(self) -> None:
        interval = self.config.flush_interval
        last_item = time.monotonic()
        dirty = False
        reported_drops = 0
        last_t = 0.0
        chunk_frames = 0
        try:
            while True:
                stopping = self._service.stopping
                with self._lock:
                    items = list(self._queue)
                    self._queue.clear()
                    dropped = self._counts["dropped"]
                for item in items:
                    try:
                        self._write_item(item)
                    except (TypeError, ValueError, AttributeError) as exc:  # a malformed item: skip it, say so
                        self._message = f"recording to {self.path}; skipped an unwritable item: {exc}"
                        self._previous = None  # a gap: the next frame is a keyframe
                        continue
                    last_t = item[1].time if item[0] == "f" else (item[4] if item[0] == "d" else item[1])
                    dirty = True
                    chunk_frames += item[0] == "f"
                    # a chunk holds at most chunk_frames frames (counted, never timed) and bytes up to chunk_size
                    if chunk_frames >= self.config.chunk_frames or self._chunk_bytes >= self.config.chunk_size:
                        self._close_chunk()
                        dirty, chunk_frames = False, 0
                if items:
                    last_item = time.monotonic()
                if dropped > reported_drops and self._origin is not None:
                    self._add(TOPIC_EVENT, last_t, event_message(last_t, "recorder",
                                                                 f"queue full: {dropped - reported_drops} items dropped"))
                    reported_drops = dropped
                if dirty and (stopping or time.monotonic() - last_item >= interval):  # idle: write what is open
                    self._close_chunk()
                    dirty, chunk_frames = False, 0
                if stopping:
                    break
                self._service.wait(min(0.02, interval / 4))
            self._writer.finish()
            self._file.flush()
            self._bytes = self._file.tell()
            self._file.close()
            with self._lock:
                self._state = "closed"
                self._message = f"recorded {self._counts['frames']} frames to {self.path}"
                if self._foxglove_errors:
                    self._message += f"; {self._foxglove_error} ({self._foxglove_errors} frames)"
        except Exception as exc:  # noqa: BLE001 - a full disk above all; whatever it is, the run goes on
            self._fail("failed", f"recording stopped: cannot write {self.path}: {_reason(exc)}; the run goes on")

    def _fail(self, state: str, message: str) -> None:
        with self._lock:
            self._state = state
            self._message = message
            self._counts["dropped"] += len(self._queue)
            self._queue.clear()
        f, self._file = self._file, None
        if f is not None:
            try:
                f.close()
            except OSError:
                pass


def _reason(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.strerror:
        return exc.strerror
    return str(exc) or type(exc).__name__
