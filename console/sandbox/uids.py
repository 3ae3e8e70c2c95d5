"""A uid of its own for every sandboxed run, from a large range, never shared with a live or unclean holder.

When swarmdeck runs as root, each run's script drops to a uid picked here (so RLIMIT_NPROC
applies: the kernel never enforces it for uid 0), and no two runs — of one researcher or
of two — share kernel state that is keyed by uid (keyrings, process limits, signals).

:func:`allocate` picks a uid uniformly from :data:`UID_RANGE` (a run cannot count runs
by its uid) and reserves it with an ``O_EXCL`` file in a root-only folder on ``/run``
(a tmpfs: reservations live exactly as long as the kernel state they protect); a uid
that has a live process or owns keys is skipped. :func:`release` ends every process of
the uid, clears its keyrings (:func:`swarmdeck.console.sandbox.keyrings.clear_user_keyrings`)
and frees the reservation — or keeps it, so the uid is never handed out again, when
something of the run survived.
"""
from __future__ import annotations

import os
import secrets
from pathlib import Path

from swarmdeck.console.sandbox.keyrings import clear_user_keyrings, uids_with_keys
from swarmdeck.core.errors import SwarmdeckError

UID_RANGE = (1 << 20, 1 << 31)
"""Half-open range of per-run uids: far above every distribution's system and login uids."""
STATE_DIR = Path("/run/swarmdeck/uids")
"""Where reservations live (root-only)."""


class UidUnavailable(RuntimeError, SwarmdeckError):
    """No per-run uid could be reserved (the message says why)."""


def _processes_of(uid: int) -> bool:
    from swarmdeck.console.sandbox.confinement import processes_of

    return bool(processes_of(uid))


def allocate(state_dir: Path = STATE_DIR, attempts: int = 64) -> int:
    """A fresh uid of :data:`UID_RANGE`, reserved until :func:`release`. UidUnavailable when none could be."""
    try:
        state_dir.mkdir(mode=0o700, parents=True, exist_ok=True)
        os.chmod(state_dir, 0o700)
    except OSError as exc:
        raise UidUnavailable(f"cannot keep per-run uid reservations in {state_dir}: {exc}") from exc
    low, high = UID_RANGE
    with_keys = uids_with_keys()
    for _ in range(attempts):
        uid = low + secrets.randbelow(high - low)
        try:
            os.close(os.open(state_dir / str(uid), os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o600))
        except FileExistsError:
            continue
        except OSError as exc:
            raise UidUnavailable(f"cannot reserve a per-run uid in {state_dir}: {exc}") from exc
        if uid in with_keys or _processes_of(uid):
            continue  # someone else's (or an unclean) uid: stays reserved, never handed out
        return uid
    raise UidUnavailable(f"no free per-run uid found in {attempts} attempts")


def release(uid: int, state_dir: Path = STATE_DIR, *, processes_gone: bool = False) -> str | None:
    """End every process of ``uid``, clear its keyrings, free its reservation; None, or what survived
    (then the reservation stays and the uid is never used again).

    ``processes_gone``: the caller knows no process of the uid is left (the run's cgroup, which
    every process of the run was born into, was removed: the kernel refuses that while it holds
    a task), so the scan of /proc is skipped.
    """
    from swarmdeck.console.sandbox.confinement import kill_all_of

    survivors = [] if processes_gone else kill_all_of(uid)
    if survivors:
        return f"processes {survivors} of uid {uid} survived the run"
    try:
        clear_user_keyrings(uid)
    except OSError as exc:
        return str(exc)
    try:
        (state_dir / str(uid)).unlink()
    except FileNotFoundError:
        pass
    return None
