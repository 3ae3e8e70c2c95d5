"""How a sandboxed child is confined: the Linux-namespace jail, the seccomp filter, the run's uid, cgroup and limits.

Two jails build the same thing (REFERENCE.md §11, §18): a new network namespace
(only its own loopback: the host's services, 127.0.0.1 included, are out of
reach), new pid/ipc/uts/mount namespaces, and a filesystem built from read-only
binds of what Python needs (the interpreter, its libraries, the installed
packages, swarmdeck's own modules, :func:`jail_layout`) plus the script's folder
read-only and a private scratch folder, the only writable place:

* ``"unshare"`` — the namespaces made with the kernel's calls, as ``unshare(1)``
  does, around a fork of a pre-imported fork server
  (:mod:`swarmdeck.console.sandbox.namespaces`, :mod:`swarmdeck.console.sandbox.zygote`):
  no Python start-up per run. Needs root or unprivileged user namespaces.
* ``"bwrap"`` — Debian's bubblewrap, a new Python process per run.

Both jails add, before any user code runs (issue 24):

* **a fresh anonymous session keyring** (keyrings are not namespaced: the script
  would otherwise share the keyring of whoever started swarmdeck),
  :mod:`swarmdeck.console.sandbox.keyrings`;
* **a seccomp filter** built with libseccomp (:mod:`swarmdeck.console.sandbox.seccomp`):
  no keyrings, no new namespaces (``unshare``, ``setns``, ``clone`` with ``CLONE_NEW*``,
  ``clone3``), no mounts, no io_uring, bpf, perf_event_open, userfaultfd, ptrace,
  process_vm_*, kexec or modules. bubblewrap loads it with ``--seccomp FD``; the
  ``unshare`` jail's script process loads it itself after its uid drop. (bubblewrap's
  ``--disable-userns`` needs ``--unshare-user``, which as root would map the script to
  host uid 0: not used; the filter refuses every way into a new user namespace.)
* **a uid of the run's own** when swarmdeck runs as root (:mod:`swarmdeck.console.sandbox.uids`:
  random in 2^20 … 2^31, reserved, never shared with a live holder; after the run all its
  processes are killed and its user keyrings cleared), so RLIMIT_NPROC bounds a fork
  bomb (the kernel never enforces it for uid 0), plus no_new_privs;
* **a cgroup of the run's own** (:mod:`swarmdeck.console.sandbox.cgroups`, v2 or v1): the
  run's total memory without swap (:attr:`SandboxLimits.memory`; an OOM kill ends the run,
  ``ended_by == "memory"``), processes (``pids.max``), CPU bandwidth and the cores it was
  given (cpuset: widening its CPU affinity has no effect);
* **scratch as a tmpfs of its own**, limited in bytes and inodes
  (:attr:`SandboxLimits.scratch_bytes`, :attr:`SandboxLimits.scratch_inodes`): a full
  scratch is ``ENOSPC`` for the script, nothing on the host's disk.

:class:`JailConfig` says which to try in which order (default: ``unshare``, then
``bwrap``); :func:`choose_jail` picks the first that works here and otherwise says
why none does — then untrusted code is refused unless the caller passes
``trusted=True``. Where no cgroup can be created (not root, no controllers), untrusted
code is likewise refused unless the operator passed ``allow_no_cgroup``
(``--allow-no-cgroup``); the run's :class:`~swarmdeck.console.sandbox.run.SandboxOutcome`
then says that it ran without one.
"""
from __future__ import annotations

import functools
import importlib.util
import os
import shutil
import signal
import subprocess
import sys
import sysconfig
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from swarmdeck.core.checks import require_positive
from swarmdeck.core.errors import SwarmdeckError


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
        tick_s: per-tick compute budget from sending poses to receiving commands: CPU time of the run's
            processes (``tick_clock="cpu"``, measured by the trusted side from the run's cgroup, so a
            loaded machine does not make a cheap script overrun), else wall time. A tick that overruns
            stops the robots for that tick.
        tick_clock: ``"cpu"`` (default; wall time where the run has no cgroup that counts CPU time) or
            ``"wall"`` (a real-time arena, where the robots cannot wait).
        tick_wall_s: with ``tick_clock="cpu"``, the wall-time backstop of a tick (a script that sleeps or
            blocks); None: ``max(10 × tick_s, tick_s + 5)`` s.
        max_overruns: that many overrun ticks in a row end the run.
        address_space: RLIMIT_AS.
        open_files: RLIMIT_NOFILE.
        processes: RLIMIT_NPROC (processes and threads of the run's uid) and the run cgroup's
            ``pids.max`` (plus the jail's own two processes).
        file_size: RLIMIT_FSIZE (largest file the child may write in its scratch dir).
        log_bytes: bytes of the child's stdout/stderr kept (the rest is counted, not kept).
        memory: bytes of memory all the run's processes together may hold (its cgroup; no swap).
        cpu_cores: CPU bandwidth of the whole run, in cores (its cgroup's quota).
        scratch_bytes: size of the scratch tmpfs, bytes.
        scratch_inodes: files and folders the scratch tmpfs can hold.
    """

    cpu_s: int = 300
    wall_s: float = 600.0
    boot_s: float = 120.0
    startup_s: float = 30.0
    tick_s: float = 1.0
    tick_clock: str = "cpu"
    tick_wall_s: float | None = None
    max_overruns: int = 5
    address_space: int = 2 << 30
    open_files: int = 64
    processes: int = 32
    file_size: int = 16 << 20
    log_bytes: int = 64 << 10
    memory: int = 2 << 30
    cpu_cores: float = 1.0
    scratch_bytes: int = 64 << 20
    scratch_inodes: int = 4096

    def __post_init__(self) -> None:
        require_positive(self, ("cpu_s", "wall_s", "boot_s", "startup_s", "tick_s", "max_overruns", "address_space",
                                "open_files", "processes", "file_size", "log_bytes", "memory", "cpu_cores",
                                "scratch_bytes", "scratch_inodes"))
        if self.tick_clock not in ("cpu", "wall"):
            raise ValueError(f"tick_clock must be 'cpu' or 'wall', got {self.tick_clock!r}")
        if self.tick_wall_s is not None and not (self.tick_wall_s >= self.tick_s):
            raise ValueError(f"tick_wall_s must be >= tick_s ({self.tick_s} s), got {self.tick_wall_s!r}")

    @property
    def tick_backstop_s(self) -> float:
        """Wall seconds a tick may take at most, whatever clock charges its budget."""
        if self.tick_clock == "wall":
            return self.tick_s
        return self.tick_wall_s if self.tick_wall_s is not None else max(10 * self.tick_s, self.tick_s + 5.0)

    def rlimits(self) -> dict[str, int]:
        """The setrlimit values the child applies to itself (names of :mod:`resource` constants)."""
        return {"RLIMIT_CPU": int(self.cpu_s), "RLIMIT_AS": int(self.address_space),
                "RLIMIT_NOFILE": int(self.open_files), "RLIMIT_NPROC": int(self.processes),
                "RLIMIT_FSIZE": int(self.file_size), "RLIMIT_CORE": 0}


class ConfinementUnavailable(RuntimeError, SwarmdeckError):
    """This machine cannot confine a child (the message says why); untrusted code is refused."""


JAILS = ("unshare", "bwrap")


@dataclass(frozen=True)
class JailConfig:
    """Which jails to use, in order of preference; the first that works on this machine wins.

    Attributes:
        order: names from :data:`JAILS`.
        bwrap: the bubblewrap executable (a name on PATH or a path).
        allow_no_cgroup: run untrusted code even where no cgroup can be created for the run
            (then only the per-process resource limits bound its memory, processes and CPU).
            An operator's choice (``--allow-no-cgroup``), never the default.
        script_env: the lab's script environment (``--script-env PATH``), a virtual environment bound
            read-only in the jail: scripts import only its packages besides the standard library,
            swarmdeck and numpy (:mod:`swarmdeck.console.sandbox.script_env`); None: what swarmdeck's own
            environment has.
    """

    order: tuple[str, ...] = JAILS
    bwrap: str = "bwrap"
    allow_no_cgroup: bool = False
    script_env: str | None = None

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
    from swarmdeck.console.sandbox.zygote import ForkServerError, shared_fork_server

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
    """None when this machine can confine untrusted code as ``config`` asks, else why not: no jail of
    ``config`` works, the seccomp filter cannot be built, or no cgroup can be created for a run
    (unless ``config.allow_no_cgroup``)."""
    from swarmdeck.console.sandbox import cgroups, seccomp

    reason = choose_jail(config)[1]
    if reason is not None:
        return reason
    reason = seccomp.probe()
    if reason is not None:
        return f"no seccomp filter: {reason}"
    if not config.allow_no_cgroup and (reason := cgroups.probe()) is not None:
        return f"{reason}; pass --allow-no-cgroup to run without a per-run limit of memory, processes and CPU"
    return None


def describe(config: JailConfig = JailConfig()) -> str:
    """One line for a server's start-up: how untrusted code is confined here, e.g. "unshare jail, seccomp filter,
    cgroup v1 per run, a uid per run" — or what is missing ("NOT CONFINED: …", "no cgroup: …")."""
    from swarmdeck.console.sandbox import cgroups, seccomp

    jail, reason = choose_jail(config)
    if jail is None:
        return f"NOT CONFINED: {reason}"
    parts = [f"{jail} jail"]
    parts.append("seccomp filter" if seccomp.probe() is None else f"NO seccomp filter ({seccomp.probe()})")
    cg = cgroups.version()
    parts.append(f"cgroup v{cg} per run" if cg is not None else f"NO cgroup per run ({cgroups.probe()})")
    parts.append("a uid per run" if os.geteuid() == 0 else "the server's own uid")
    return ", ".join(parts)


def processes_of(uid: int) -> list[int]:
    """Pids of live processes whose real uid is ``uid`` (from /proc/PID/status)."""
    pids = []
    wanted = f"\nUid:\t{int(uid)}\t".encode()
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            fd = os.open(f"/proc/{entry}/status", os.O_RDONLY)
        except OSError:
            continue
        try:
            head = os.read(fd, 2048)  # Uid: is within the first ten lines
        except OSError:
            continue
        finally:
            os.close(fd)
        if wanted in head:
            pids.append(int(entry))
    return pids


def kill_until_gone(pids: Callable[[], list[int]], timeout: float = 10.0, pause: float = 0.01) -> list[int]:
    """SIGKILL the processes ``pids()`` lists, again and again, until it lists none (or ``timeout`` s pass);
    returns the survivors. ``pids``: e.g. the processes of a uid (:func:`processes_of`) or of a cgroup."""
    deadline = time.monotonic() + timeout
    while True:
        alive = pids()
        if not alive or time.monotonic() > deadline:
            return alive
        for pid in alive:
            try:
                os.kill(pid, signal.SIGKILL)
            except (ProcessLookupError, PermissionError):
                pass
        time.sleep(pause)


def kill_all_of(uid: int, timeout: float = 10.0) -> list[int]:
    """SIGKILL every process of ``uid`` until none is left (or ``timeout`` s); returns the survivors.

    The jail's pid namespace dies with its first process, but asynchronously; this makes the
    end of a run synchronous, so no process of a finished run can touch the next one.
    """
    return kill_until_gone(lambda: processes_of(uid), timeout)


#: Every top-level swarmdeck package (pyproject.toml's ``[tool.setuptools] packages``, first level):
#: the jail binds each one's folder (editable installs live outside site-packages), so a package
#: missing here is a crash of every jailed script that imports it. One list; a test keeps it equal
#: to pyproject.toml's (tests/sandbox/test_sandbox_jail_packages.py).
SWARMDECK_PACKAGES: tuple[str, ...] = (
    "console", "core", "coverage", "devices", "envs", "examples", "inputs", "network", "safety", "sensing",
    "tracking",
)


@functools.lru_cache(maxsize=1)
def _system_paths() -> tuple[Path, ...]:
    """What Python and swarmdeck need, read-only (computed once: sysconfig and resolving are slow)."""
    roots = {Path("/usr")}
    roots |= {p for p in map(Path, ("/lib", "/lib64", "/bin", "/lib32", "/libx32")) if p.exists() and not p.is_symlink()}
    roots |= {Path(sys.prefix), Path(sys.base_prefix), Path(sys.executable).resolve().parent.parent}
    for key in ("stdlib", "platstdlib", "purelib", "platlib"):
        roots.add(Path(sysconfig.get_paths()[key]))
    for name in SWARMDECK_PACKAGES:  # editable installs live outside site-packages
        spec = importlib.util.find_spec(f"swarmdeck.{name}")
        if spec is None or not spec.submodule_search_locations:
            raise RuntimeError(f"swarmdeck.{name} (in SWARMDECK_PACKAGES) is not an installed package")
        roots |= {Path(location).resolve() for location in spec.submodule_search_locations}
    paths = [p.resolve() for p in sorted(roots) if p.exists()]
    # drop paths inside another bound path
    return tuple(p for p in paths if not any(p != q and p.is_relative_to(q) for q in paths))


def _visible_paths(script_dir: Path, extra: tuple[Path, ...] = ()) -> list[tuple[str, Path]]:
    """(kind, path) binds of the jail: what Python and swarmdeck need, the script's folder and ``extra``
    (the script environment), read-only."""
    return [("ro", p) for p in _system_paths()] + [("ro", script_dir.resolve())] + [("ro", p.resolve()) for p in extra]


_MERGED_USR_LINKS = ("/lib", "/lib64", "/bin", "/sbin", "/lib32", "/libx32")


def jail_layout(script_dir: Path, scratch: Path | None = None, extra: tuple[Path, ...] = ()
                ) -> tuple[list[tuple[str, Path]], list[tuple[str, Path]]]:
    """What the jail's filesystem holds: binds ``("ro" | "rw", path)`` (each at its own path; a
    host ``scratch`` folder, when given, the only "rw" one — else scratch is a tmpfs the jail
    mounts itself; ``extra`` folders read-only: the script environment) and symlinks
    ``(target, path)`` (merged /usr: /lib -> usr/lib)."""
    symlinks = [(os.readlink(link), link) for link in map(Path, _MERGED_USR_LINKS) if link.is_symlink()]
    rw = [] if scratch is None else [("rw", scratch.resolve())]
    return _visible_paths(script_dir, extra) + rw, symlinks


def bwrap_command(child_argv: list[str], script_dir: Path, scratch: Path, bwrap: str = "bwrap", *,
                  seccomp_fd: int | None = None, scratch_size: int | None = None,
                  extra: tuple[Path, ...] = ()) -> list[str]:
    """The bubblewrap command line running ``child_argv`` in the jail (scratch writable).

    ``scratch`` is bound from the host's view at its own path (the trusted side mounts a
    limited tmpfs there in bwrap's private mount namespace first, see
    :mod:`swarmdeck.console.sandbox.run`) — or, with ``scratch_size``, is a tmpfs of that
    many bytes bwrap makes itself (``--size``; no inode limit: for runs without root).
    ``seccomp_fd``: a readable descriptor holding the filter's BPF (``--seccomp``).
    ``extra``: more folders bound read-only (the script environment).
    """
    argv = [shutil.which(bwrap) or bwrap, "--unshare-net", "--unshare-pid", "--unshare-ipc", "--unshare-uts",
            "--die-with-parent", "--new-session", "--proc", "/proc", "--dev", "/dev", "--tmpfs", "/tmp"]
    made: set[Path] = {Path("/"), Path("/proc"), Path("/dev"), Path("/tmp")}
    binds, symlinks = jail_layout(script_dir, extra=extra)
    for target, link in symlinks:
        argv += ["--symlink", target, str(link)]
        made.add(link)
    scratch = scratch.resolve()
    for kind, path in [*binds, ("scratch", scratch)]:
        for parent in reversed(path.parents):  # parents first, world-traversable (bwrap makes them 0700)
            if parent not in made:
                argv += ["--perms", "0755", "--dir", str(parent)]
                made.add(parent)
        if kind == "scratch":
            argv += (["--bind", str(path), str(path)] if scratch_size is None else
                     ["--perms", "0700", "--size", str(int(scratch_size)), "--tmpfs", str(path)])
        else:
            argv += ["--ro-bind" if kind == "ro" else "--bind", str(path), str(path)]
        made.add(path)
    if seccomp_fd is not None:
        argv += ["--seccomp", str(seccomp_fd)]
    argv += ["--chdir", str(scratch), "--"]
    return argv + child_argv
