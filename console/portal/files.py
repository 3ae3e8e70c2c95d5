"""The portal's file modes: its data folder and everything under it are private to the server's user.

Other local users of the machine must not read researchers' scripts, recordings or the database, so:

* folders are ``0700`` (:data:`DIR_MODE`) and files ``0600`` (:data:`FILE_MODE`), set explicitly where the
  portal creates them (:func:`private_dir`, :func:`write_private`);
* ``swarmdeck server`` (and the exports' child process) run with the umask ``077`` (:data:`UMASK`), so files
  that libraries create on the portal's behalf (SQLite's WAL, the recorder, the exports) get the same modes.

The jail's own copy of a script (outside the data folder, for the sandboxed uid to read) is made by
:mod:`swarmdeck.console.sandbox.run` with the modes it needs.
"""
from __future__ import annotations

import os
from pathlib import Path

DIR_MODE = 0o700
FILE_MODE = 0o600
UMASK = 0o077


def private_dir(path: Path) -> Path:
    """Create ``path`` (and missing parents) if need be and make it ``0700`` — also when it existed with wider
    modes (a data folder of an older swarmdeck); the path."""
    path.mkdir(parents=True, exist_ok=True, mode=DIR_MODE)
    os.chmod(path, DIR_MODE)
    return path


def private_file(path: Path) -> Path:
    """Create ``path`` empty if it does not exist, and make it ``0600``; the path."""
    fd = os.open(path, os.O_WRONLY | os.O_CREAT, FILE_MODE)
    try:
        os.fchmod(fd, FILE_MODE)
    finally:
        os.close(fd)
    return path


def write_private(path: Path, data: bytes | str) -> None:
    """Write ``data`` (str: UTF-8) to ``path``, replacing what was there, the file ``0600`` from its creation on."""
    raw = data.encode("utf-8") if isinstance(data, str) else data
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, FILE_MODE)
    try:
        os.fchmod(fd, FILE_MODE)
        view = memoryview(raw)
        while view:
            view = view[os.write(fd, view):]
    finally:
        os.close(fd)
