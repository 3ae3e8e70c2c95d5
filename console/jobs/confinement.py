"""How a sandboxed child is confined: resource limits and the Linux-namespace jail.

Two jails build the same thing (REFERENCE.md §11): a new network namespace
(only its own loopback: the host's services, 127.0.0.1 included, are out of
reach), new pid/ipc/uts/mount namespaces, and a filesystem built from read-only
binds of what Python needs (the interpreter, its libraries, the installed
packages, swarmdeck's own modules, :func:`jail_layout`) plus the script's folder
read-only and a private scratch directory, the only writable place:

* ``"unshare"`` — the namespaces made with the kernel's calls, as ``unshare(1)``
  does, around a fork of a pre-imported fork server
  (:mod:`swarmdeck.console.jobs.namespaces`, :mod:`swarmdeck.console.jobs.zygote`):
  no Python start-up per run. Needs root or unprivileged user namespaces.
* ``"bwrap"`` — Debian's bubblewrap, a new Python process per run.

:class:`JailConfig` says which to try in which order (default: ``unshare``, then
``bwrap``); :func:`choose_jail` picks the first that works here and otherwise says
why none does — then untrusted code is refused unless the caller passes
``trusted=True``. When swarmdeck runs as root, the child drops to a uid of its
own before user code runs (so RLIMIT_NPROC bounds a fork bomb: the kernel never
enforces it for uid 0), and sets no_new_privs.
"""
from __future__ import annotations

import functools
import os
import shutil
import subprocess
import sys
import sysconfig
from dataclasses import dataclass
from pathlib import Path

from swarmdeck.core.checks import require_positive


@dataclass(frozen=True)
class SandboxLimits:
    """Per-child limits. Times in seconds, sizes in bytes.

    Attributes:
        cpu_s: RLIMIT_CPU, CPU seconds of the child (SIGXCPU/SIGKILL past it).
        wall_s: wall-clock limit of a whole run (the child is killed past it).
        boot_s: wall time allowed for the child to load swarmdeck and confine itself (not the
            script's time: a loaded machine can take seconds here).
        startup_s: wall time allowed from then until the script has built its Arena
            (its imports and top-level code).
        tick_s: per-tick compute budget: wall time from sending poses to receiving commands.
            A tick that overruns stops the robots for that tick.
        max_overruns: that many overrun ticks in a row end the run.
        address_space: RLIMIT_AS.
        open_files: RLIMIT_NOFILE.
        processes: RLIMIT_NPROC (processes and threads of the child's uid).
        file_size: RLIMIT_FSIZE (largest file the child may write in its scratch dir).
        log_bytes: bytes of the child's stdout/stderr kept (the rest is counted, not kept).
    """

    cpu_s: int = 300
    wall_s: float = 600.0
    boot_s: float = 120.0
    startup_s: float = 30.0
    tick_s: float = 1.0
    max_overruns: int = 5
    address_space: int = 2 << 30
    open_files: int = 64
    processes: int = 32
    file_size: int = 16 << 20
    log_bytes: int = 64 << 10

    def __post_init__(self) -> None:
        require_positive(self, ("cpu_s", "wall_s", "boot_s", "startup_s", "tick_s", "max_overruns", "address_space",
                                "open_files", "processes", "file_size", "log_bytes"))

    def rlimits(self) -> dict[str, int]:
        """The setrlimit values the child applies to itself (names of :mod:`resource` constants)."""
        return {"RLIMIT_CPU": int(self.cpu_s), "RLIMIT_AS": int(self.address_space),
                "RLIMIT_NOFILE": int(self.open_files), "RLIMIT_NPROC": int(self.processes),
                "RLIMIT_FSIZE": int(self.file_size), "RLIMIT_CORE": 0}


class ConfinementUnavailable(RuntimeError):
    """This machine cannot confine a child (the message says why); untrusted code is refused."""


JAILS = ("unshare", "bwrap")


@dataclass(frozen=True)
class JailConfig:
    """Which jails to use, in order of preference; the first that works on this machine wins.

    Attributes:
        order: names from :data:`JAILS`.
        bwrap: the bubblewrap executable (a name on PATH or a path).
    """

    order: tuple[str, ...] = JAILS
    bwrap: str = "bwrap"

    def __post_init__(self) -> None:
        order = tuple(self.order) if isinstance(self.order, (list, tuple)) else (self.order,)
        if not order or any(j not in JAILS for j in order) or len(set(order)) != len(order):
            raise ValueError(f"jail order must name some of {', '.join(JAILS)} once each, got {self.order!r}")
        object.__setattr__(self, "order", order)


@functools.lru_cache(maxsize=8)
def probe_bwrap(bwrap: str = "bwrap") -> str | None:
    """None when bubblewrap can build the jail here, else the reason it cannot (cached)."""
    exe = shutil.which(bwrap)
    if exe is None:
        return f"bubblewrap ({bwrap}) is not installed (Debian: apt-get install bubblewrap)"
    try:
        out = subprocess.run([exe, "--ro-bind", "/", "/", "--unshare-net", "--unshare-pid", "--die-with-parent",
                              "true"], capture_output=True, timeout=20, check=False)
    except (OSError, subprocess.TimeoutExpired) as exc:
        return f"bwrap could not start: {exc}"
    if out.returncode != 0:
        return f"bwrap cannot create namespaces here: {out.stderr.decode(errors='replace').strip()[:200]}"
    return None


def probe_unshare() -> str | None:
    """None when the fork server can build ``unshare`` jails here, else the reason it cannot."""
    from swarmdeck.console.jobs.zygote import ForkServerError, shared_fork_server

    try:
        reason = shared_fork_server().unavailable
    except ForkServerError as exc:
        return str(exc)
    return None if reason is None else f"Linux namespaces are not available here: {reason}"


def choose_jail(config: JailConfig = JailConfig()) -> tuple[str | None, str | None]:
    """(the first jail of ``config.order`` that works here, None) or (None, why none does)."""
    reasons = []
    for jail in config.order:
        reason = probe_unshare() if jail == "unshare" else probe_bwrap(config.bwrap)
        if reason is None:
            return jail, None
        reasons.append(f"{jail}: {reason}")
    return None, "; ".join(reasons)


def probe(config: JailConfig = JailConfig()) -> str | None:
    """None when some jail of ``config`` works here, else why none does."""
    return choose_jail(config)[1]


def sandbox_uid() -> int | None:
    """A uid of the child's own when running as root (so RLIMIT_NPROC applies), else None."""
    if os.geteuid() != 0:
        return None
    return 200000 + os.getpid() % 100000


def processes_of(uid: int) -> list[int]:
    """Pids of live processes whose real uid is ``uid`` (from /proc/PID/status)."""
    pids = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/status", encoding="ascii", errors="replace") as f:
                for line in f:
                    if line.startswith("Uid:"):
                        if int(line.split()[1]) == uid:
                            pids.append(int(entry))
                        break
        except (FileNotFoundError, ProcessLookupError, PermissionError, ValueError):
            continue
    return pids


def kill_all_of(uid: int, timeout: float = 10.0) -> list[int]:
    """SIGKILL every process of ``uid`` until none is left (or ``timeout`` s); returns the survivors.

    The jail's pid namespace dies with its first process, but asynchronously; this makes the
    end of a run synchronous, so no process of a finished run can touch the next one.
    """
    import signal
    import time

    deadline = time.monotonic() + timeout
    while True:
        pids = processes_of(uid)
        if not pids or time.monotonic() > deadline:
            return pids
        for pid in pids:
            try:
                os.kill(pid, signal.SIGKILL)
            except (ProcessLookupError, PermissionError):
                pass
        time.sleep(0.01)


@functools.lru_cache(maxsize=1)
def _system_paths() -> tuple[Path, ...]:
    """What Python and swarmdeck need, read-only (computed once: sysconfig and resolving are slow)."""
    import swarmdeck.console
    import swarmdeck.core
    import swarmdeck.coverage
    import swarmdeck.devices
    import swarmdeck.safety

    roots = {Path("/usr")}
    roots |= {p for p in map(Path, ("/lib", "/lib64", "/bin", "/lib32", "/libx32")) if p.exists() and not p.is_symlink()}
    roots |= {Path(sys.prefix), Path(sys.base_prefix), Path(sys.executable).resolve().parent.parent}
    for key in ("stdlib", "platstdlib", "purelib", "platlib"):
        roots.add(Path(sysconfig.get_paths()[key]))
    for module in (swarmdeck.console, swarmdeck.core, swarmdeck.coverage, swarmdeck.devices, swarmdeck.safety):
        roots.add(Path(module.__file__).resolve().parent)  # editable installs live outside site-packages
    paths = [p.resolve() for p in sorted(roots) if p.exists()]
    # drop paths inside another bound path
    return tuple(p for p in paths if not any(p != q and p.is_relative_to(q) for q in paths))


def _visible_paths(script_dir: Path) -> list[tuple[str, Path]]:
    """(kind, path) binds of the jail: what Python and swarmdeck need, and the script's folder, read-only."""
    return [("ro", p) for p in _system_paths()] + [("ro", script_dir.resolve())]


_MERGED_USR_LINKS = ("/lib", "/lib64", "/bin", "/sbin", "/lib32", "/libx32")


def jail_layout(script_dir: Path, scratch: Path) -> tuple[list[tuple[str, Path]], list[tuple[str, Path]]]:
    """What the jail's filesystem holds: binds ``("ro" | "rw", path)`` (each at its own path; the
    scratch folder the only "rw" one) and symlinks ``(target, path)`` (merged /usr: /lib -> usr/lib)."""
    symlinks = [(os.readlink(link), link) for link in map(Path, _MERGED_USR_LINKS) if link.is_symlink()]
    return _visible_paths(script_dir) + [("rw", scratch.resolve())], symlinks


def bwrap_command(child_argv: list[str], script_dir: Path, scratch: Path, bwrap: str = "bwrap") -> list[str]:
    """The bubblewrap command line running ``child_argv`` in the jail (scratch writable)."""
    argv = [shutil.which(bwrap) or bwrap, "--unshare-net", "--unshare-pid", "--unshare-ipc", "--unshare-uts",
            "--die-with-parent", "--new-session", "--proc", "/proc", "--dev", "/dev", "--tmpfs", "/tmp"]
    made: set[Path] = {Path("/"), Path("/proc"), Path("/dev"), Path("/tmp")}
    binds, symlinks = jail_layout(script_dir, scratch)
    for target, link in symlinks:
        argv += ["--symlink", target, str(link)]
        made.add(link)
    for kind, path in binds:
        for parent in reversed(path.parents):  # parents first, world-traversable (bwrap makes them 0700)
            if parent not in made:
                argv += ["--perms", "0755", "--dir", str(parent)]
                made.add(parent)
        argv += ["--ro-bind" if kind == "ro" else "--bind", str(path), str(path)]
        made.add(path)
    argv += ["--chdir", str(scratch.resolve()), "--"]
    return argv + child_argv
