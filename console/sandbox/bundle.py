"""What a sandboxed run executes: one script file, or a folder of files with an entry script.

A :class:`ScriptBundle` holds the files themselves (relative path → bytes), not
paths on this machine: it travels with a verification task to any worker (a
local pool, a Ray node without a shared disk), and :meth:`ScriptBundle.write_to`
lays it out in a fresh folder that the sandbox binds read-only into the jail.
The entry script runs with its folder first on ``sys.path``, so sibling
modules and packages (``helpers.py``, ``lib/__init__.py``) are importable.

Build one with :meth:`ScriptBundle.from_path` (a ``.py`` file, or a directory and
its entry file) or :meth:`ScriptBundle.from_files` (e.g. an extracted upload).
Everything from outside is checked, with a :class:`ValueError` naming the
problem: relative POSIX paths only (no ``..``, no absolute paths, no empty or
hidden-control names), regular files only (symlinks are refused, never
followed), at most :data:`MAX_FILES` files and :data:`MAX_BYTES` bytes in all,
an entry that is a ``.py`` file of the bundle.
"""
from __future__ import annotations

import hashlib
import os
import stat
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path, PurePosixPath

MAX_FILES = 256
MAX_BYTES = 8 << 20  # all files together
MAX_DEPTH = 8  # folder levels
DEFAULT_ENTRY = "main.py"


def _check_name(name: str) -> str:
    """``name`` as a normalised relative POSIX path; ValueError when it could leave the folder."""
    if not isinstance(name, str) or not name or "\x00" in name or "\\" in name:
        raise ValueError(f"bad file name in the bundle: {name!r}")
    path = PurePosixPath(name)
    parts = path.parts
    if path.is_absolute() or any(p in ("..", ".", "") for p in parts) or str(path) != name:
        raise ValueError(f"file name {name!r} must be a relative path inside the bundle (no '..', no leading '/')")
    if len(parts) > MAX_DEPTH:
        raise ValueError(f"file name {name!r} is nested deeper than {MAX_DEPTH} folders")
    if any(ord(c) < 32 for c in name):
        raise ValueError(f"file name {name!r} contains control characters")
    return str(path)


@dataclass(frozen=True)
class ScriptBundle:
    """An experiment's files and the one that runs.

    Attributes:
        entry: relative path of the script to run (a ``.py`` file among ``files``).
        files: ``(relative path, bytes)`` pairs, sorted by path.
    """

    entry: str
    files: tuple[tuple[str, bytes], ...]

    def __post_init__(self) -> None:
        names = [_check_name(name) for name, _ in self.files]
        if len(set(names)) != len(names):
            raise ValueError("the bundle names a file twice")
        if len(names) > MAX_FILES:
            raise ValueError(f"the bundle has {len(names)} files, more than the limit of {MAX_FILES}")
        total = sum(len(data) for _, data in self.files)
        if total > MAX_BYTES:
            raise ValueError(f"the bundle is {total} bytes, more than the limit of {MAX_BYTES}")
        as_dirs = {str(p) for n in names for p in PurePosixPath(n).parents}
        if as_dirs & set(names):
            raise ValueError(f"{sorted(as_dirs & set(names))[0]!r} is both a file and a folder in the bundle")
        entry = _check_name(self.entry)
        if not entry.endswith(".py"):
            raise ValueError(f"the entry script {entry!r} must be a Python file (.py)")
        if entry not in names:
            raise ValueError(f"the entry script {entry!r} is not among the bundle's files")
        object.__setattr__(self, "entry", entry)
        object.__setattr__(self, "files", tuple(sorted(zip(names, (bytes(d) for _, d in self.files)))))

    @classmethod
    def single(cls, name: str, source: bytes) -> ScriptBundle:
        """One script file called ``name`` (its base name is used)."""
        base = PurePosixPath(str(name).replace("\\", "/")).name
        return cls(base, ((base, bytes(source)),))

    @classmethod
    def from_files(cls, files: Mapping[str, bytes], entry: str = DEFAULT_ENTRY) -> ScriptBundle:
        """From a mapping relative path → bytes (e.g. the members of an uploaded archive)."""
        return cls(entry, tuple(files.items()))

    @classmethod
    def from_path(cls, path: str | Path, entry: str | None = None) -> ScriptBundle:
        """A ``.py`` file (``entry`` must be None), or a directory with its entry file (default ``main.py``).

        Hidden files and folders (names starting with '.') and ``__pycache__`` are left out;
        symlinks and special files inside the directory are refused.
        """
        p = Path(path)
        if p.is_file():
            if entry is not None:
                raise ValueError(f"an entry file is only for a directory; {str(p)!r} is a file")
            if p.suffix != ".py":
                raise ValueError(f"script {str(p)!r} must be a Python file (.py) or a directory; archives are not accepted")
            size = p.stat().st_size
            if size > MAX_BYTES:
                raise ValueError(f"script {str(p)!r} is {size} bytes, more than the limit of {MAX_BYTES}")
            return cls.single(p.name, p.read_bytes())
        if not p.is_dir():
            raise ValueError(f"script {str(p)!r} does not exist or is neither a file nor a directory")
        files: dict[str, bytes] = {}
        total = 0
        for folder, dirs, names in os.walk(p, followlinks=False):
            dirs[:] = sorted(d for d in dirs if not d.startswith(".") and d != "__pycache__")
            for d in dirs:
                if os.path.islink(os.path.join(folder, d)):
                    raise ValueError(f"{os.path.join(folder, d)!r} is a symlink: a bundle holds regular files only")
            for name in sorted(names):
                if name.startswith("."):
                    continue
                full = os.path.join(folder, name)
                info = os.lstat(full)
                if not stat.S_ISREG(info.st_mode):
                    raise ValueError(f"{full!r} is not a regular file (symlinks are not followed)")
                total += info.st_size
                if len(files) >= MAX_FILES or total > MAX_BYTES:
                    raise ValueError(f"directory {str(p)!r} holds more than {MAX_FILES} files or {MAX_BYTES} bytes")
                with open(full, "rb") as f:
                    files[Path(full).relative_to(p).as_posix()] = f.read()
        return cls(entry if entry is not None else DEFAULT_ENTRY, tuple(files.items()))

    @property
    def name(self) -> str:
        """What reports call the experiment: the entry's path inside the bundle."""
        return self.entry

    @property
    def source(self) -> bytes:
        """The entry script's bytes."""
        return dict(self.files)[self.entry]

    @property
    def sha256(self) -> str:
        """Hex digest: of the script's bytes for a single file, else of every (path, bytes) in order."""
        if len(self.files) == 1:
            return hashlib.sha256(self.files[0][1]).hexdigest()
        h = hashlib.sha256()
        for name, data in self.files:
            encoded = name.encode()
            h.update(len(encoded).to_bytes(8, "little") + encoded + len(data).to_bytes(8, "little") + data)
        return h.hexdigest()

    def write_to(self, folder: Path, *, file_mode: int = 0o644, dir_mode: int = 0o755) -> Path:
        """Write the files under ``folder`` (default world-readable, folders 0755, for the jail's uid; the portal's
        own copy is 0600/0700); returns the entry's path."""
        for name, data in self.files:
            target = folder / name
            for parent in reversed(target.relative_to(folder).parents):
                d = folder / parent
                if not d.exists():
                    d.mkdir(mode=dir_mode)
                    os.chmod(d, dir_mode)
            fd = os.open(target, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, file_mode)
            with os.fdopen(fd, "wb") as f:
                os.fchmod(f.fileno(), file_mode)
                f.write(data)
        return folder / self.entry
