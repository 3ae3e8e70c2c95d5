"""What a researcher submits: the experiment manifest and the script upload, checked before anything is stored.

**Manifest** (JSON object; :func:`parse_manifest`): ``name`` (1-100 printable
characters), ``robots`` (integer N, 1 … the arena's fleet), ``duration``
(seconds, > 0 and at most the configured maximum), optional ``initial_poses``
(N rows ``[x, y, θ]`` in m, rad: checked by ``console.sandbox.start_poses.check_initial_poses``,
inside the arena and pairwise at least ``MIN_SEPARATION`` apart — the same check as a script's own
initial conditions), optional
``no_barrier`` (bool: the request to run without the barrier, granted only if
verification allows it and no operator forbids it), optional ``entry`` (the
script inside a ``.zip``), optional ``params`` (an object of the values
``swarmdeck.devices.params()`` returns in the script: names it declares, values of the declared defaults' kinds —
checked against the script's declaration by :func:`check_declared`; verification and the arena run both use them).
Unknown keys are refused. Every error is a
:class:`~swarmdeck.console.portal.errors.BadInput` naming the key.

**Upload** (:func:`check_upload`): a ``.py`` (UTF-8 text, at most
``bundle.MAX_BYTES``) or a ``.zip`` holding the script and,
optionally, ``manifest.json``. Archives are read in memory, never extracted by
name: members with absolute names, ``..``, backslashes, drive letters, names
outside ``[A-Za-z0-9_.-]`` per component or starting with a dot, symbolic links,
duplicates, more than ``max_members`` members, a member larger than
``max_member_bytes`` (checked on the bytes actually inflated, not the size the
archive claims) or more than ``max_total_bytes`` in all are refused. The
uploaded file's own name is used only for its suffix and is displayed
sanitised; the job's files live under names the portal chooses.

Archives become a :class:`~swarmdeck.console.sandbox.bundle.ScriptBundle` (its
checks and limits apply too): the entry script (manifest ``entry``, else
``main.py``, else the only ``.py`` file) runs with its sibling modules importable.
"""
from __future__ import annotations

import io
import json
import math
import re
import stat
import zipfile
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from swarmdeck.console.portal.arenas import NAME_RE, NEEDS
from swarmdeck.console.portal.errors import BadInput, TooLarge, Unsupported
from swarmdeck.console.sandbox.bundle import MAX_BYTES, ScriptBundle
from swarmdeck.console.sandbox.start_poses import check_initial_poses
from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds

MANIFEST_KEYS = ("name", "robots", "duration", "initial_poses", "no_barrier", "entry", "arena", "needs", "params")
#: the most script parameters a manifest may set, and the longest text value
MAX_PARAMS = 64
MAX_PARAM_TEXT = 200
COMPONENT_RE = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.-]{0,99}$")
MANIFEST_NAME = "manifest.json"


@dataclass(frozen=True)
class Limits:
    """What a submission may be. Sizes in bytes, times in s."""

    fleet: int = 12
    bounds: Bounds = DEFAULT_BOUNDS
    max_duration: float = 600.0
    max_upload_bytes: int = 4 << 20
    max_members: int = 64
    max_member_bytes: int = 1 << 20
    max_total_bytes: int = 4 << 20


@dataclass(frozen=True)
class Manifest:
    name: str
    robots: int
    duration: float
    initial_poses: tuple[tuple[float, float, float], ...] | None = None
    no_barrier: bool = False
    entry: str | None = None
    arena: str | None = None  # the arena the job must run on (None: any that fits; issue 30)
    needs: str = "either"  # physical | simulated | either robots
    #: the script's parameter values (``swarmdeck.devices.params``; None: its defaults), name -> bool|int|float|str
    params: tuple[tuple[str, bool | int | float | str], ...] | None = None

    def to_dict(self) -> dict[str, Any]:
        d: dict[str, Any] = {"name": self.name, "robots": self.robots, "duration": self.duration,
                             "no_barrier": self.no_barrier}
        if self.initial_poses is not None:
            d["initial_poses"] = [list(p) for p in self.initial_poses]
        if self.entry is not None:
            d["entry"] = self.entry
        if self.arena is not None:
            d["arena"] = self.arena
        if self.needs != "either":
            d["needs"] = self.needs
        if self.params is not None:
            d["params"] = dict(self.params)
        return d


@dataclass(frozen=True)
class Upload:
    """A checked upload: ``kind`` "py" or "zip", ``files`` relative name -> bytes, ``entry`` the script to run
    (None: an archive whose entry the manifest must name)."""

    kind: str
    display_name: str
    files: dict[str, bytes] = field(default_factory=dict)
    entry: str | None = "script.py"
    manifest: dict[str, Any] | None = None  # manifest.json from inside an archive, if any


def display_name(filename: str | None) -> str:
    """The uploaded name for display only: its last component, characters outside ``[A-Za-z0-9_.-]`` replaced."""
    base = re.split(r"[\\/]", filename or "")[-1]
    clean = re.sub(r"[^A-Za-z0-9_.-]", "_", base)[-100:].lstrip(".")
    return clean or "script"


def json_object(data: Any, what: str) -> dict[str, Any]:
    """A request's JSON object (``what``: the form field it came in, e.g. "manifest") from JSON text or an already
    parsed object; :class:`BadInput` naming ``what`` when it is not valid JSON or not an object."""
    if isinstance(data, (str, bytes)):
        try:
            data = json.loads(data)
        except (ValueError, UnicodeDecodeError) as exc:
            raise BadInput(f"the {what} is not valid JSON: {exc}", what) from None
    if not isinstance(data, dict):
        raise BadInput(f"the {what} must be a JSON object, got {type(data).__name__}", what)
    return data


def parse_manifest(data: Any, limits: Limits, first: int = 0) -> Manifest:
    """The manifest from a JSON text (or an already parsed object); :class:`BadInput` naming the key."""
    data = json_object(data, "manifest")
    manifest, errors = _checked(data, limits, first)
    if errors:
        raise errors[0]
    assert manifest is not None
    return manifest


def manifest_errors(data: dict[str, Any], limits: Limits, first: int = 0) -> list[BadInput]:
    """Every problem of a manifest object, one per key, in the manifest's order (:func:`parse_manifest`
    raises the first): a form shows them all at once."""
    return _checked(data, limits, first)[1]


def _checked(data: dict[str, Any], limits: Limits, first: int = 0) -> tuple[Manifest | None, list[BadInput]]:
    """The manifest (None when anything is wrong) and the problems, each key checked on its own; poses are
    numbered from ``first`` in messages, and the messages say so (0: the JSON list's index; 1: the Submit
    page's lines)."""
    errors: list[BadInput] = []

    def check(key: str, fn: Any) -> Any:
        try:
            return fn()
        except BadInput as exc:
            errors.append(exc)
            return None

    unknown = sorted(set(data) - set(MANIFEST_KEYS))
    if unknown:
        errors.append(BadInput(f"unknown manifest key {unknown[0]!r} (known: {', '.join(MANIFEST_KEYS)})", unknown[0]))
    name = check("name", lambda: _name(data))
    robots = check("robots", lambda: _robots(data, limits))
    duration = check("duration", lambda: _duration(data, limits))
    no_barrier = check("no_barrier", lambda: _no_barrier(data))
    entry = check("entry", lambda: _entry(data))
    arena = check("arena", lambda: _arena(data))
    needs = check("needs", lambda: _needs(data))
    params = check("params", lambda: parse_params(data.get("params")))
    poses = data.get("initial_poses")
    if poses is not None:  # with a bad robot count the poses are still checked (against their own count)
        n = robots if robots is not None else (len(poses) if isinstance(poses, list) else 0)
        poses = check("initial_poses", lambda: _initial_poses(poses, n, limits.bounds, first))
    if errors:
        return None, errors
    return Manifest(name, robots, float(duration), poses, no_barrier, entry, arena, needs, params), []


def _required(data: dict[str, Any], key: str) -> Any:
    if key not in data:
        raise BadInput(f"the manifest needs {key!r}", key)
    return data[key]


def _name(data: dict[str, Any]) -> str:
    name = _required(data, "name")
    if not isinstance(name, str) or not 1 <= len(name.strip()) <= 100 or not name.isprintable():
        raise BadInput("name must be 1-100 printable characters", "name")
    return name.strip()


def _robots(data: dict[str, Any], limits: Limits) -> int:
    robots = _required(data, "robots")
    if isinstance(robots, bool) or not isinstance(robots, int):
        raise BadInput(f"robots must be an integer, got {robots!r}", "robots")
    if not 1 <= robots <= limits.fleet:
        raise BadInput(f"robots must be between 1 and {limits.fleet} (the robots this arena has), got {robots}",
                       "robots")
    return robots


def _duration(data: dict[str, Any], limits: Limits) -> float:
    duration = _required(data, "duration")
    if isinstance(duration, bool) or not isinstance(duration, (int, float)) or not math.isfinite(duration):
        raise BadInput(f"duration must be a number of seconds, got {duration!r}", "duration")
    if not 0 < duration <= limits.max_duration:
        raise BadInput(f"duration must be > 0 and at most {limits.max_duration:g} s, got {duration:g}", "duration")
    return float(duration)


def _no_barrier(data: dict[str, Any]) -> bool:
    no_barrier = data.get("no_barrier", False)
    if not isinstance(no_barrier, bool):
        raise BadInput(f"no_barrier must be true or false, got {no_barrier!r}", "no_barrier")
    return no_barrier


def _arena(data: dict[str, Any]) -> str | None:
    """The arena the job asks for by name (None: any); whether this portal has it is the service's check."""
    arena = data.get("arena")
    if arena is None:
        return None
    if not isinstance(arena, str) or not NAME_RE.match(arena):
        raise BadInput(f"arena must be an arena's name (lower-case letters, digits, '-', '_'), got {arena!r}", "arena")
    return arena


def _needs(data: dict[str, Any]) -> str:
    needs = data.get("needs", "either")
    if needs not in NEEDS:
        raise BadInput(f"needs must be one of {', '.join(NEEDS)}, got {needs!r}", "needs")
    return str(needs)


def parse_params(value: Any) -> tuple[tuple[str, bool | int | float | str], ...] | None:
    """A manifest's ``params`` (None: not given): an object of at most :data:`MAX_PARAMS` identifiers, each a
    bool, a finite number or printable text of at most :data:`MAX_PARAM_TEXT` characters; :class:`BadInput`
    naming ``params`` and the offending name otherwise. Sorted by name (one job, one order)."""
    if value is None:
        return None
    if not isinstance(value, dict):
        raise BadInput(f"params must be an object of parameter values, got {type(value).__name__}", "params")
    if len(value) > MAX_PARAMS:
        raise BadInput(f"params may set at most {MAX_PARAMS} parameters, got {len(value)}", "params")
    out: list[tuple[str, bool | int | float | str]] = []
    for name, v in sorted(value.items()):
        if not isinstance(name, str) or not name.isidentifier() or len(name) > 64:
            raise BadInput(f"params: {name!r} is not a parameter name (an identifier of at most 64 characters)",
                           "params")
        if isinstance(v, float) and not math.isfinite(v):
            raise BadInput(f"params: {name} must be finite, got {v!r}", "params")
        if isinstance(v, str) and (len(v) > MAX_PARAM_TEXT or not v.isprintable()):
            raise BadInput(f"params: {name} must be printable text of at most {MAX_PARAM_TEXT} characters",
                           "params")
        if not isinstance(v, (bool, int, float, str)):
            raise BadInput(f"params: {name} must be a number, true/false or text, got {type(v).__name__}", "params")
        out.append((name, v))
    return tuple(out)


def check_declared(bundle: ScriptBundle, params: tuple[tuple[str, Any], ...] | None) -> None:
    """:class:`BadInput` (``params``) when ``params`` names a parameter the bundle's entry script does not declare
    with ``swarmdeck.devices.params(...)``, or a value that does not fit the declared default's kind (the message
    names the declared ones); nothing to check for None."""
    if params is None:
        return
    from swarmdeck.devices.experiment_params import ParamError, declared_in_source, resolve

    try:
        declared = declared_in_source(bundle.source.decode("utf-8", "replace"), bundle.entry) or {}
        resolve(declared, dict(params))
    except (ParamError, SyntaxError) as exc:
        raise BadInput(f"params: {exc}", "params") from None
    except (MemoryError, RecursionError):  # the parser's own bound on nesting
        raise BadInput("the script nests expressions deeper than Python's parser allows", "script") from None


def _entry(data: dict[str, Any]) -> str | None:
    entry = data.get("entry")
    if entry is not None and (not isinstance(entry, str) or not _safe_name(entry) or not entry.endswith(".py")):
        raise BadInput("entry must be the relative name of a .py file in the archive", "entry")
    return entry


def _initial_poses(poses: Any, n: int, bounds: Bounds, first: int = 0) -> tuple[tuple[float, float, float], ...]:
    try:
        arr = np.asarray(poses, dtype=float)  # JSON has no int/float distinction: 0 means 0.0 here
    except (TypeError, ValueError):
        raise BadInput("initial_poses must be a list of [x, y, theta] number triples", "initial_poses") from None
    try:
        arr = check_initial_poses(arr, n, bounds, f"initial_poses (numbered from {first})", first=first)
    except ValueError as exc:
        raise BadInput(str(exc), "initial_poses") from None
    return tuple((float(x), float(y), float(t)) for x, y, t in arr)


def _safe_name(name: str) -> bool:
    parts = name.split("/")
    return all(COMPONENT_RE.match(p) for p in parts) and len(parts) <= 8


def check_upload(filename: str | None, data: bytes, limits: Limits) -> Upload:
    """The checked upload (see the module docstring); BadInput / TooLarge / Unsupported naming ``script``."""
    shown = display_name(filename)
    if len(data) > limits.max_upload_bytes:
        raise TooLarge(f"the upload is {len(data)} bytes, more than the limit of {limits.max_upload_bytes}", "script")
    suffix = shown.lower().rsplit(".", 1)[-1] if "." in shown else ""
    if suffix == "py":
        if len(data) > MAX_BYTES:
            raise TooLarge(f"a script may be at most {MAX_BYTES} bytes, this one is {len(data)}", "script")
        _text(data, "script")
        return Upload("py", shown, {"script.py": data}, "script.py")
    if suffix == "zip":
        return _check_zip(shown, data, limits)
    raise Unsupported("upload a Python script (.py) or a .zip archive holding one", "script")


def _text(data: bytes, field_name: str) -> str:
    if b"\x00" in data:
        raise BadInput("the script is not text (it holds NUL bytes)", field_name)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise BadInput(f"the script is not UTF-8 text: {exc}", field_name) from None


def _check_zip(shown: str, data: bytes, limits: Limits) -> Upload:
    try:
        archive = zipfile.ZipFile(io.BytesIO(data))
        infos = archive.infolist()
    except (zipfile.BadZipFile, ValueError, EOFError) as exc:
        raise BadInput(f"the archive cannot be read as a zip file: {exc}", "script") from None
    if len(infos) > limits.max_members:
        raise TooLarge(f"the archive has {len(infos)} members, more than {limits.max_members}", "script")
    files: dict[str, bytes] = {}
    total = 0
    for info in infos:
        name = info.filename
        if info.is_dir():
            continue
        if (name.startswith("/") or "\\" in name or ":" in name or any(p in ("", ".", "..") for p in name.split("/"))
                or not _safe_name(name)):
            raise BadInput(f"archive member {name[:120]!r}: only plain relative names are allowed "
                           "(no absolute paths, '..', backslashes or unusual characters)", "script")
        mode = info.external_attr >> 16
        if stat.S_IFMT(mode) not in (0, stat.S_IFREG):  # 0: no type recorded (Windows tools, zipfile.writestr)
            raise BadInput(f"archive member {name!r} is a link or a special file", "script")
        if name in files:
            raise BadInput(f"archive member {name!r} appears twice", "script")
        if info.file_size > limits.max_member_bytes:
            raise TooLarge(f"archive member {name!r} is {info.file_size} bytes, more than {limits.max_member_bytes}",
                           "script")
        try:
            with archive.open(info) as member:
                content = member.read(limits.max_member_bytes + 1)
        except (zipfile.BadZipFile, RuntimeError, OSError, NotImplementedError, EOFError) as exc:
            raise BadInput(f"archive member {name!r} cannot be read: {exc}", "script") from None
        if len(content) > limits.max_member_bytes:
            raise TooLarge(f"archive member {name!r} inflates to more than {limits.max_member_bytes} bytes", "script")
        total += len(content)
        if total > limits.max_total_bytes:
            raise TooLarge(f"the archive inflates to more than {limits.max_total_bytes} bytes", "script")
        files[name] = content
    manifest = None
    if MANIFEST_NAME in files:
        try:
            manifest = json.loads(files.pop(MANIFEST_NAME).decode("utf-8"))
        except (ValueError, UnicodeDecodeError) as exc:
            raise BadInput(f"{MANIFEST_NAME} in the archive is not valid JSON: {exc}", "manifest") from None
    scripts = sorted(n for n in files if n.endswith(".py"))
    if not scripts:
        raise BadInput("the archive holds no .py script", "script")
    entry = manifest.get("entry") if isinstance(manifest, dict) else None
    if not isinstance(entry, str):  # None: the manifest sent beside the archive must name it
        entry = "main.py" if "main.py" in files else (scripts[0] if len(scripts) == 1 else None)
    for name in scripts:
        _text(files[name], "script")
    return Upload("zip", shown, files, entry, manifest)


def check_bundle(files: dict[str, bytes], entry: str | None) -> ScriptBundle:
    """The sandbox's own checks on an archive's files and entry (BadInput naming ``entry`` or ``script``)."""
    if entry is None:
        raise BadInput("the archive holds several .py files and no main.py: name the one to run in the "
                       "manifest's 'entry'", "entry")
    if entry not in files:
        raise BadInput(f"the entry {entry!r} is not in the archive", "entry")
    try:
        return ScriptBundle.from_files(files, entry)
    except ValueError as exc:
        raise BadInput(str(exc), "script") from None
