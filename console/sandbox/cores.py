"""A core of its own for a worker process that does not know its index (a Ray worker): claimed on this machine.

The local pool hands worker k core k (executors.py). A Ray worker has no index, and Ray places tasks without
pinning them; the sandboxed run's two processes (the trusted loop and the script) take turns every tick and
cost least on one core of their own (bench/RESULTS.md "verification"). :func:`claim_core` pins the calling
process to the first of its allowed cores that no other process holds: each core has a lock file in
``folder`` and the process keeps an exclusive ``flock`` on it for as long as it lives (the kernel drops it when
the process ends, however it ends). A process already pinned to one core keeps it; when every core is held the
process stays unpinned.
"""
from __future__ import annotations

import fcntl
import os
from pathlib import Path

#: where the lock files live (one per core, ``core-<k>.lock``; machine-local, like the run uids' reservations)
CORES_DIR = Path("/run/swarmdeck/cores")


def claim_core(folder: Path = CORES_DIR) -> int | None:
    """Pin this process to a core no other claimant on this machine holds; the core, or None (no core free, or
    this machine cannot pin). Idempotent: a process pinned to one core already returns it."""
    if not hasattr(os, "sched_getaffinity"):
        return None
    allowed = sorted(os.sched_getaffinity(0))
    if len(allowed) == 1:
        return allowed[0]
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError:
        return None
    for core in allowed:
        try:
            fd = os.open(folder / f"core-{core}.lock", os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o600)
        except OSError:
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:  # another process holds this core
            os.close(fd)
            continue
        try:
            os.sched_setaffinity(0, {core})
        except OSError:
            os.close(fd)
            return None
        return core  # the fd stays open (and locked) for this process's life: the claim ends with the process
    return None
