"""Capsule files: the capsule inside a recording, and ``run.zip`` (writer and careful reader).

Inside a recording (:class:`~swarmdeck.console.recording.recorder.Recorder` ``capsule=``): the manifest is the
``swarmdeck.capsule`` metadata record right after the header, the script files are attachments
``capsule/<relative path>`` before the first chunk. :func:`read_recorded_capsule` reads both back.

A capsule zip (``swarmdeck capsule RECORDING -o run.zip``, :func:`write_capsule`) holds::

    manifest.json        the manifest (capsule.Manifest.to_dict(): files with SHA-256, run, environment, hash)
    files/<path>         the script files, byte for byte
    recording.mcap       the recording the run is compared with (its SHA-256 in the manifest)

:func:`open_capsule` refuses, with a message naming what is wrong: a file that is not a zip, a zip without
``manifest.json``, a member whose name leaves its folder (``..``, absolute, backslash) or is a link, members too large,
a manifest from a newer capsule format or a newer swarmdeck (naming both versions), and every file whose bytes do not
hash to the manifest's SHA-256 (one line per file). It writes members only below the folder it is given, by name
checks before any byte is written (never ``extractall``).
"""
from __future__ import annotations

import json
import os
import stat
import zipfile
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from swarmdeck.console.recording.capsule import (
    ATTACHMENT_PREFIX,
    CAPSULE_FORMAT,
    CAPSULE_METADATA_NAME,
    Manifest,
    check_relative_path,
    is_newer,
    package_version,
    sha256_hex,
)
from swarmdeck.core.errors import SwarmdeckError

MANIFEST_NAME = "manifest.json"
RECORDING_NAME = "recording.mcap"
FILES_DIR = "files/"
#: Largest total of uncompressed member bytes a capsule may hold (a zip bomb is refused before extraction).
MAX_CAPSULE_BYTES = 4 * 1024**3


class CapsuleError(ValueError, SwarmdeckError):
    """A capsule that cannot be used: not a zip, no manifest, unsafe names, tampered, from a newer swarmdeck."""


@dataclass(frozen=True)
class RecordedCapsule:
    """The capsule a recording carries: its ``manifest`` (None: recorded before capsules, or without one) and the
    script ``files`` (relative path → bytes) from its attachments."""

    manifest: Manifest | None
    files: dict[str, bytes] = field(default_factory=dict)


@dataclass(frozen=True)
class OpenedCapsule:
    """A checked, extracted capsule: its ``manifest``, the ``folder`` holding its files (``folder / entry``), and the
    extracted ``recording``."""

    manifest: Manifest
    folder: Path
    recording: Path

    @property
    def entry_path(self) -> Path | None:
        """The file that runs (None: a capsule without a script, e.g. a console session)."""
        return None if self.manifest.entry is None else self.folder / self.manifest.entry


def read_recorded_capsule(path: str | os.PathLike[str]) -> RecordedCapsule:
    """The capsule inside the recording at ``path`` (the records between its header and its first chunk).

    CapsuleError when the file is not a swarmdeck recording, the manifest is malformed or an attachment's bytes do
    not hash to the manifest's SHA-256 (naming the file)."""
    from swarmdeck.console.recording.codec import decode_metadata
    from swarmdeck.console.recording.mcap_walk import (
        MAGIC,
        OP_ATTACHMENT,
        OP_CHUNK,
        OP_HEADER,
        OP_MESSAGE,
        OP_METADATA,
        McapFile,
        parse_record,
    )

    p = Path(path)
    try:
        f = open(p, "rb")
    except OSError as exc:
        raise CapsuleError(f"cannot open {p}: {exc.strerror or exc}") from None
    with f:
        size = os.fstat(f.fileno()).st_size
        mf = McapFile(f, size)
        head = mf.head(len(MAGIC)) if size > len(MAGIC) and mf.read(0, len(MAGIC)) == MAGIC else None
        if head is None or head.op != OP_HEADER:
            raise CapsuleError(f"{p} is not an MCAP recording")
        manifest_data: Any = None
        files: dict[str, bytes] = {}
        for rec in mf.walk(head.end):
            if rec.op in (OP_CHUNK, OP_MESSAGE):
                break  # the capsule is written before any message
            try:
                if rec.op == OP_METADATA:
                    m = parse_record(OP_METADATA, mf.body(rec))
                    if m.name == CAPSULE_METADATA_NAME:
                        manifest_data = decode_metadata(dict(m.metadata)).get("manifest")
                elif rec.op == OP_ATTACHMENT:
                    a = parse_record(OP_ATTACHMENT, mf.body(rec))
                    if a.name.startswith(ATTACHMENT_PREFIX):
                        files[a.name[len(ATTACHMENT_PREFIX):]] = bytes(a.data)
            except Exception as exc:  # noqa: BLE001 - a damaged record: the mcap package's errors
                raise CapsuleError(f"{p}: damaged capsule record at byte {rec.offset}: {exc}") from None
    if manifest_data is None:
        return RecordedCapsule(None, files)
    try:
        manifest = Manifest.from_dict(manifest_data)
    except ValueError as exc:
        raise CapsuleError(f"{p}: {exc}") from None
    problems = [f"{name}: missing from the recording" for name in manifest.files if name not in files]
    problems += [f"{name}: SHA-256 {sha256_hex(data)} is not the manifest's {manifest.files[name]}"
                 for name, data in sorted(files.items()) if name in manifest.files
                 and sha256_hex(data) != manifest.files[name]]
    if problems:
        raise CapsuleError(f"{p}: the recorded script files do not match their manifest:\n  " + "\n  ".join(problems))
    return RecordedCapsule(manifest, {k: files[k] for k in manifest.files})


def write_capsule(recording: str | os.PathLike[str], out: str | os.PathLike[str], *,
                  capsule: RecordedCapsule | None = None) -> Path:
    """Write the capsule zip of ``recording`` to ``out`` (layout in the module docstring) and return its path.

    ``capsule``: the manifest and files (None: the ones the recording carries, :func:`read_recorded_capsule`).
    CapsuleError when the recording carries no capsule (recorded before capsules) or cannot be read."""
    rec = Path(recording)
    got = capsule if capsule is not None else read_recorded_capsule(rec)
    if got.manifest is None:
        raise CapsuleError(f"{rec} carries no capsule (recorded by a swarmdeck before capsules, or not by a run): "
                           "nothing says which script and settings made it")
    try:
        data = rec.read_bytes()
    except OSError as exc:
        raise CapsuleError(f"cannot read {rec}: {exc.strerror or exc}") from None
    manifest = Manifest(**{**_fields(got.manifest), "recording": {"name": RECORDING_NAME, "sha256": sha256_hex(data)}})
    dest = Path(out)
    dest.parent.mkdir(parents=True, exist_ok=True)
    tmp = dest.with_name(dest.name + ".part")
    with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        zf.writestr(MANIFEST_NAME, json.dumps(manifest.to_dict(), indent=2, sort_keys=True))
        for name in sorted(got.files):
            zf.writestr(FILES_DIR + check_relative_path(name), got.files[name])
        zf.writestr(RECORDING_NAME, data, compress_type=zipfile.ZIP_STORED)  # MCAP chunks are compressed already
    os.replace(tmp, dest)
    return dest


#: Largest total of script bytes a capsule takes from a folder (a script folder is small; this is not a data store).
MAX_SCRIPT_BYTES = 64 * 1024**2


def script_files(script: str | os.PathLike[str], entry: str | None = None) -> tuple[dict[str, bytes], str]:
    """The files of a script and its entry point: a file → ``{its name: bytes}``; a folder → every regular file below
    it (hidden ones too: the sandbox sees them; no links, no ``__pycache__``), entry ``entry`` or ``main.py``. CapsuleError for a script
    that cannot be read or a folder over :data:`MAX_SCRIPT_BYTES`."""
    p = Path(script)
    try:
        if not p.is_dir():
            return {p.name: p.read_bytes()}, p.name
        files: dict[str, bytes] = {}
        total = 0
        for f in sorted(p.rglob("*")):
            rel = f.relative_to(p)
            if f.is_symlink() or not f.is_file() or "__pycache__" in rel.parts:
                continue
            data = f.read_bytes()
            total += len(data)
            if total > MAX_SCRIPT_BYTES:
                raise CapsuleError(f"{p}: the script folder holds more than {MAX_SCRIPT_BYTES} bytes")
            files[rel.as_posix()] = data
    except OSError as exc:
        raise CapsuleError(f"cannot read the script {p}: {exc.strerror or exc}") from None
    main = entry or "main.py"
    if main not in files:
        raise CapsuleError(f"{p}: no entry file {main!r} in the script folder")
    return files, main


def _fields(m: Manifest) -> dict[str, Any]:
    return {"kind": m.kind, "environment": m.environment, "files": m.files, "entry": m.entry, "run": m.run,
            "key": m.key, "recording": m.recording, "format": m.format}


def _member_problem(info: zipfile.ZipInfo) -> str | None:
    """Why a zip member may not be extracted (None: it may)."""
    mode = info.external_attr >> 16
    if mode and stat.S_ISLNK(mode):
        return f"zip member {info.filename!r} is a symbolic link (refused)"
    if info.is_dir():
        return None
    try:
        check_relative_path(info.filename)
    except ValueError as exc:
        return f"zip member {info.filename!r}: path traversal refused ({exc})"
    return None


def open_capsule(path: str | os.PathLike[str], into: str | os.PathLike[str], *,
                 max_bytes: int = MAX_CAPSULE_BYTES) -> OpenedCapsule:
    """Check the capsule zip at ``path`` and extract it below the folder ``into`` (module docstring for what is
    refused); CapsuleError naming every problem found."""
    p, root = Path(path), Path(into)
    if not zipfile.is_zipfile(p):
        raise CapsuleError(f"{p} is not a capsule: not a zip file (make one with `swarmdeck capsule RECORDING -o run.zip`)")
    try:
        zf = zipfile.ZipFile(p)
    except (OSError, zipfile.BadZipFile) as exc:
        raise CapsuleError(f"{p} is not a readable zip file: {exc}") from None
    with zf:
        infos = zf.infolist()
        bad = [msg for info in infos if (msg := _member_problem(info)) is not None]
        if bad:
            raise CapsuleError(f"{p} refused:\n  " + "\n  ".join(bad))
        total = sum(i.file_size for i in infos)
        if total > max_bytes:
            raise CapsuleError(f"{p} refused: its members hold {total} bytes uncompressed, more than {max_bytes}")
        names = {i.filename for i in infos}
        if MANIFEST_NAME not in names:
            raise CapsuleError(f"{p} is not a capsule: no {MANIFEST_NAME} in the zip")
        try:
            raw = json.loads(zf.read(MANIFEST_NAME).decode("utf-8"))
        except (ValueError, UnicodeDecodeError, zipfile.BadZipFile) as exc:
            raise CapsuleError(f"{p}: {MANIFEST_NAME} is not JSON: {exc}") from None
        _refuse_newer(p, raw)
        try:
            manifest = Manifest.from_dict(raw)
        except ValueError as exc:
            raise CapsuleError(f"{p}: {exc}") from None
        if manifest.recording is None or manifest.recording["name"] not in names:
            raise CapsuleError(f"{p}: the capsule holds no recording (manifest 'recording' or the zip member missing)")
        wanted = {FILES_DIR + name: digest for name, digest in manifest.files.items()}
        wanted[manifest.recording["name"]] = manifest.recording["sha256"]
        problems = []
        for member, digest in sorted(wanted.items()):
            if member not in names:
                problems.append(f"{member}: missing from the zip")
                continue
            try:
                data = zf.read(member)
            except (zipfile.BadZipFile, OSError) as exc:  # a CRC error: bytes changed inside the zip
                problems.append(f"{member}: unreadable ({exc})")
                continue
            got = sha256_hex(data)
            if got != digest:
                problems.append(f"{member}: SHA-256 {got} is not the manifest's {digest} (the file was changed)")
                continue
            target = root / member
            target.parent.mkdir(parents=True, exist_ok=True)
            target.write_bytes(data)
        extra = sorted(n for n in names - set(wanted) - {MANIFEST_NAME} if not n.endswith("/"))
        problems += [f"{n}: not listed in the manifest" for n in extra]
        if problems:
            raise CapsuleError(f"{p} is tampered or incomplete (hash mismatch per file):\n  " + "\n  ".join(problems))
    return OpenedCapsule(manifest, root / FILES_DIR.rstrip("/"), root / manifest.recording["name"])


def _refuse_newer(p: Path, raw: Any) -> None:
    """CapsuleError for a manifest from a newer capsule format or a newer swarmdeck (naming both)."""
    if not isinstance(raw, Mapping):
        return
    fmt = raw.get("format")
    if isinstance(fmt, int) and fmt > CAPSULE_FORMAT:
        raise CapsuleError(f"{p} is in capsule format {fmt}, written by a newer swarmdeck; this swarmdeck reads "
                           f"format {CAPSULE_FORMAT}: upgrade to run it")
    env = raw.get("environment")
    theirs = env.get("swarmdeck") if isinstance(env, Mapping) else None
    ours = package_version("swarmdeck") or "0"
    if isinstance(theirs, str):
        try:
            newer = is_newer(theirs, ours)
        except ValueError:
            raise CapsuleError(f"{p}: the capsule's swarmdeck version {theirs!r} is not a version") from None
        if newer:
            raise CapsuleError(f"{p} was written by swarmdeck {theirs}, newer than this swarmdeck {ours}: "
                               f"upgrade to swarmdeck {theirs} or later to run it")


__all__ = ["FILES_DIR", "MANIFEST_NAME", "MAX_CAPSULE_BYTES", "MAX_SCRIPT_BYTES", "script_files", "RECORDING_NAME", "CapsuleError", "OpenedCapsule",
           "RecordedCapsule", "open_capsule", "read_recorded_capsule", "write_capsule"]
