"""Capsules: what reproduces a run — the format, the hashes and the environment (pure; no file I/O).

A capsule's **manifest** names everything a re-execution needs and everything that could make it differ:

* ``files``: the script files, ``{relative path: SHA-256 hex}`` (the bytes travel beside the manifest: as MCAP
  attachments inside the recording, as zip members inside ``run.zip``), and ``entry``, the file that runs;
* ``run``: the run's arguments (robots, duration, seed, safety, obstacles, robot model, rps options, the script's
  argv, sandboxed or not) — for a console session its loop, inputs and guard are in the recording's ``config``
  message, which re-simulation already reads;
* ``environment``: swarmdeck's version, Python, the platform and the versions of the packages that shape the
  numbers (:data:`PACKAGES`);
* ``key``: :func:`run_key` over the files' bytes, the entry, the arguments and the seed — the cache key of the run
  (sweeps cache finished runs by it);
* ``recording``: in a zip only, the recording's name and SHA-256.

Hashes are SHA-256 over :func:`canonical_json` (sorted keys, no spaces, NaN and ±inf refused), so equal content
gives equal hashes whatever the dict order. The writer and reader of files are in
:mod:`~swarmdeck.console.recording.capsule_zip`; the recording carries the manifest in its ``swarmdeck.capsule``
metadata record (:mod:`~swarmdeck.console.recording.recorder`).
"""
from __future__ import annotations

import hashlib
import json
import math
import platform
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

#: The manifest format this swarmdeck writes and reads (a larger one is refused with both numbers).
CAPSULE_FORMAT = 1
#: Name of the MCAP metadata record holding the manifest, and the prefix of the script files' attachments.
CAPSULE_METADATA_NAME = "swarmdeck.capsule"
ATTACHMENT_PREFIX = "capsule/"
#: The packages whose versions can change a run's numbers (the environment names them when installed).
PACKAGES = ("numpy", "scipy", "clarabel", "numba", "msgspec", "mcap", "shapely", "osqp", "qpsolvers")
#: What a run can be: ``swarmdeck run``, a console session, a verification run, a portal job.
KINDS = ("run", "console", "verification", "portal")


def canonical_json(value: Any) -> bytes:
    """``value`` as canonical JSON bytes (sorted keys, no whitespace, UTF-8); ValueError for NaN/±inf or
    a value JSON cannot hold (naming its type)."""
    try:
        return json.dumps(value, sort_keys=True, separators=(",", ":"), allow_nan=False,
                          ensure_ascii=False).encode("utf-8")
    except (TypeError, ValueError) as exc:
        raise ValueError(f"not canonical JSON: {exc}") from None


def sha256_hex(data: bytes) -> str:
    """Lower-case hex SHA-256 of ``data`` (64 characters)."""
    return hashlib.sha256(bytes(data)).hexdigest()


def check_relative_path(name: str) -> str:
    """``name`` if it is a safe relative POSIX path (no ``..``, no absolute path, no drive, no backslash, no NUL);
    ValueError naming it otherwise. Every file of a capsule is named by such a path."""
    if not isinstance(name, str) or not name or "\x00" in name or "\\" in name:
        raise ValueError(f"file name {name!r} is not a relative path")
    if name.startswith("/") or re.match(r"^[A-Za-z]:", name):
        raise ValueError(f"file name {name!r} is absolute (a capsule holds relative paths only)")
    parts = name.split("/")
    if any(p in ("", ".", "..") for p in parts):
        raise ValueError(f"file name {name!r} leaves its folder or has an empty part ('..', '.', '//')")
    return name


def file_hashes(files: Mapping[str, bytes]) -> dict[str, str]:
    """``{relative path: SHA-256 hex}`` of ``files`` (sorted by path); ValueError for an unsafe path."""
    return {check_relative_path(k): sha256_hex(files[k]) for k in sorted(files)}


def run_key(files: Mapping[str, bytes], *, entry: str | None = None, params: Mapping[str, Any] | None = None,
            seed: int | None = None, config: Mapping[str, Any] | None = None, swarmdeck: str | None = None) -> str:
    """The cache key of one run: SHA-256 hex of the canonical JSON of the script files' hashes, the entry point,
    the script parameters, the seed, the run's configuration and (when given) swarmdeck's version.

    Args:
        files: ``{relative path: bytes}`` of the script files (a single script: ``{"script.py": ...}``).
        entry: the file that runs (None: the only file).
        params: the script's parameters (JSON-able).
        seed: the run's seed (None: unseeded).
        config: arena/robot/sensor/network/obstacle/safety configuration and run arguments (JSON-able).
        swarmdeck: a version to fold in (None: left out, so the key survives upgrades).

    Same bytes and values give the same key whatever the order of the mappings; ValueError for
    something that is not JSON-able (or NaN) or an unsafe path."""
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int)):
        raise ValueError(f"seed must be an int or None, got {seed!r}")
    body = {"files": file_hashes(files), "entry": entry, "params": dict(params or {}), "seed": seed,
            "config": dict(config or {})}
    if swarmdeck is not None:
        body["swarmdeck"] = str(swarmdeck)
    return sha256_hex(canonical_json(body))


def capsule_hash(manifest: Mapping[str, Any]) -> str:
    """SHA-256 hex of a manifest's canonical JSON without its own ``hash`` key: equal hashes, the same run
    described in the same environment."""
    return sha256_hex(canonical_json({k: v for k, v in manifest.items() if k != "hash"}))


def package_version(name: str) -> str | None:
    """The installed version of distribution ``name`` (None when not installed)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version(name)
    except PackageNotFoundError:
        return None


def environment() -> dict[str, Any]:
    """This process's environment: swarmdeck's version, Python (version and implementation), the platform and
    machine, and the versions of the installed :data:`PACKAGES`."""
    packages = {p: v for p in PACKAGES if (v := package_version(p)) is not None}
    return {"swarmdeck": package_version("swarmdeck") or "0", "python": platform.python_version(),
            "implementation": platform.python_implementation(), "platform": platform.platform(),
            "machine": platform.machine(), "packages": packages}


def parse_version(text: str) -> tuple[int, ...]:
    """The leading numeric release of a version string: "0.1.0" → (0, 1, 0), "1.2rc1" → (1, 2);
    ValueError when it starts with no number."""
    nums = []
    for part in str(text).split("."):
        m = re.match(r"\d+", part)
        if m is None:
            break
        nums.append(int(m.group()))
        if m.end() != len(part):
            break
    if not nums:
        raise ValueError(f"version {text!r} has no numeric release")
    return tuple(nums)


def is_newer(version: str, than: str) -> bool:
    """True when release ``version`` is later than ``than`` (trailing zeros ignored: 1.0 == 1.0.0)."""
    a, b = list(parse_version(version)), list(parse_version(than))
    width = max(len(a), len(b))
    return a + [0] * (width - len(a)) > b + [0] * (width - len(b))


def environment_differences(recorded: Mapping[str, Any], current: Mapping[str, Any]) -> list[str]:
    """One line per difference between two :func:`environment` s that can change a run's numbers: swarmdeck,
    Python, implementation, platform, machine, each package (present in one only counts). Empty: the same."""
    out = []
    for key in ("swarmdeck", "python", "implementation", "platform", "machine"):
        a, b = recorded.get(key), current.get(key)
        if a != b:
            out.append(f"{key}: recorded {a}, here {b}")
    pa, pb = dict(recorded.get("packages") or {}), dict(current.get("packages") or {})
    for name in sorted(set(pa) | set(pb)):
        if pa.get(name) != pb.get(name):
            out.append(f"package {name}: recorded {pa.get(name, 'not installed')}, "
                       f"here {pb.get(name, 'not installed')}")
    return out


def _finite_json(value: Any, what: str) -> Any:
    """``value`` if canonical JSON can hold it (else ValueError naming ``what``)."""
    if isinstance(value, float) and not math.isfinite(value):
        raise ValueError(f"{what} is not finite: {value}")
    canonical_json(value)
    return value


@dataclass(frozen=True)
class Manifest:
    """A capsule's manifest (module docstring). ``files``: relative path → SHA-256 hex; ``run``: the run's
    arguments (JSON-able); ``recording``: ``{"name", "sha256"}`` in a zip, None inside the recording itself."""

    kind: str
    environment: dict[str, Any]
    files: dict[str, str] = field(default_factory=dict)
    entry: str | None = None
    run: dict[str, Any] = field(default_factory=dict)
    key: str = ""
    recording: dict[str, str] | None = None
    format: int = CAPSULE_FORMAT

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"capsule kind must be one of {', '.join(KINDS)}, got {self.kind!r}")
        for name, digest in self.files.items():
            check_relative_path(name)
            if not (isinstance(digest, str) and re.fullmatch(r"[0-9a-f]{64}", digest)):
                raise ValueError(f"capsule file {name!r}: {digest!r} is not a SHA-256 hex digest")
        if self.entry is not None and self.entry not in self.files:
            raise ValueError(f"capsule entry {self.entry!r} is not one of its files ({', '.join(self.files) or 'none'})")
        _finite_json(self.run, "capsule run arguments")
        _finite_json(self.environment, "capsule environment")

    @property
    def swarmdeck(self) -> str:
        """The swarmdeck version that wrote the run."""
        return str(self.environment.get("swarmdeck", "0"))

    def to_dict(self) -> dict[str, Any]:
        """The manifest as JSON-able data, with its :func:`capsule_hash` under ``hash``."""
        d: dict[str, Any] = {"format": self.format, "kind": self.kind, "environment": self.environment,
                             "entry": self.entry, "files": dict(sorted(self.files.items())), "run": self.run,
                             "key": self.key}
        if self.recording is not None:
            d["recording"] = dict(self.recording)
        d["hash"] = capsule_hash(d)
        return d

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> Manifest:
        """Rebuild from :meth:`to_dict` output; ValueError naming what is missing or malformed. A newer format
        is refused with both numbers (the swarmdeck version check is the reader's: it names both versions)."""
        if not isinstance(d, Mapping):
            raise ValueError(f"capsule manifest is not a JSON object ({type(d).__name__})")
        fmt = d.get("format")
        if not isinstance(fmt, int) or isinstance(fmt, bool):
            raise ValueError(f"capsule manifest: format missing or not an int ({fmt!r})")
        for key, typ in (("kind", str), ("environment", dict), ("files", dict), ("run", dict)):
            if not isinstance(d.get(key), typ):
                raise ValueError(f"capsule manifest: {key!r} missing or not a {typ.__name__}")
        rec = d.get("recording")
        if rec is not None and not (isinstance(rec, dict) and isinstance(rec.get("name"), str)
                                    and isinstance(rec.get("sha256"), str)):
            raise ValueError("capsule manifest: 'recording' must be {\"name\": ..., \"sha256\": ...}")
        entry = d.get("entry")
        if entry is not None and not isinstance(entry, str):
            raise ValueError(f"capsule manifest: entry must be a string, got {entry!r}")
        return cls(kind=d["kind"], environment=dict(d["environment"]), files={str(k): v for k, v in d["files"].items()},
                   entry=entry, run=dict(d["run"]), key=str(d.get("key", "")),
                   recording=None if rec is None else {"name": rec["name"], "sha256": rec["sha256"]}, format=fmt)


def manifest_for(kind: str, files: Mapping[str, bytes], *, entry: str | None = None,
                 run: Mapping[str, Any] | None = None, env: Mapping[str, Any] | None = None) -> Manifest:
    """The manifest of a run of ``kind`` over ``files`` (relative path → bytes) with arguments ``run``, in
    ``env`` (None: this process's :func:`environment`); its key is :func:`run_key` of the files, entry, the
    arguments and their ``seed``."""
    args = dict(run or {})
    seed = args.get("seed")
    key = run_key(files, entry=entry, seed=seed if isinstance(seed, int) and not isinstance(seed, bool) else None,
                  config={k: v for k, v in args.items() if k != "seed"})
    return Manifest(kind=kind, environment=dict(env if env is not None else environment()), files=file_hashes(files),
                    entry=entry, run=args, key=key)


def session_capsule(metadata: Mapping[str, Any]) -> dict[str, Any] | None:
    """The manifest (as :meth:`Manifest.to_dict`) of a console session recorded with ``metadata`` (what
    ``resimulate.session_metadata`` returns): no script files; ``run`` holds its ``config`` (loop, inputs, source,
    guard), so the key names the session's settings. None when that configuration is not JSON-able."""
    try:
        return manifest_for("console", {}, run={"config": dict(metadata.get("config") or {})}).to_dict()
    except ValueError:
        return None


__all__ = ["session_capsule", "ATTACHMENT_PREFIX", "CAPSULE_FORMAT", "CAPSULE_METADATA_NAME", "KINDS", "PACKAGES", "Manifest",
           "canonical_json", "capsule_hash", "check_relative_path", "environment", "environment_differences",
           "file_hashes", "is_newer", "manifest_for", "package_version", "parse_version", "run_key", "sha256_hex"]
