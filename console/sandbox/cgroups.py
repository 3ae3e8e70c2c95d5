"""A cgroup per sandboxed run: the run's total memory, processes and CPU, limited by the kernel.

Resource limits (setrlimit) bound one process each; a script that forks can multiply
them. The trusted side therefore creates one cgroup per run (:func:`create`), the
jail's first process joins it before any user code runs (so everything the script
starts is inside), and the trusted side removes it after the run
(:meth:`RunCgroup.remove`). Both kernel interfaces are supported:

* **cgroup v2** (the unified hierarchy with the ``memory`` and ``pids`` controllers
  enabled — systemd hosts): a group ``swarmdeck/run-…`` under the hierarchy's root with
  ``memory.max``, ``memory.swap.max = 0``, ``memory.oom.group = 1`` (an OOM kill ends the
  whole run), ``pids.max``, ``cpu.max`` and ``cpuset.cpus``/``.mems``;
* **cgroup v1** (one hierarchy per controller, what REFERENCE.md §18's machines mount): a
  group ``swarmdeck-run-…`` under this process's own group in each of the ``memory``,
  ``pids``, ``cpu`` and ``cpuset`` hierarchies, with ``memory.limit_in_bytes`` (and
  ``memory.memsw.limit_in_bytes``, no swap, where swap accounting is on), ``pids.max``,
  ``cpu.cfs_quota_us`` / ``cpu.cfs_period_us`` and ``cpuset.cpus`` / ``.mems``.

``memory`` and ``pids`` are required; ``cpu`` and ``cpuset`` are applied where mounted
(:attr:`RunCgroup.missing` names those that were not). :class:`CgroupUnavailable` says
why no group could be created (not root, no controller mounted, …): then the sandbox
refuses untrusted code unless the operator allowed runs without one
(:attr:`swarmdeck.console.sandbox.confinement.JailConfig.allow_no_cgroup`). Groups left by a
swarmdeck killed mid-run are removed by :func:`sweep` (the fork server runs it when it starts).
"""
from __future__ import annotations

import os
import secrets
import time
from dataclasses import dataclass
from pathlib import Path

from swarmdeck.console.sandbox.confinement import kill_until_gone
from swarmdeck.core.checks import require_positive
from swarmdeck.core.errors import SwarmdeckError
from swarmdeck.core.service_thread import ServiceThread

CGROUP_ROOT = Path("/sys/fs/cgroup")
REQUIRED = ("memory", "pids")
OPTIONAL = ("cpu", "cpuset")
ACCOUNTING_V1 = "cpuacct"  # v1's CPU-time accounting (v2 has cpu.stat in every group): joined when mounted
CPU_PERIOD_US = 100_000


class CgroupUnavailable(RuntimeError, SwarmdeckError):
    """No cgroup can be created for a run here (the message says why)."""


@dataclass(frozen=True)
class CgroupLimits:
    """What one run may use in total, all its processes together.

    Attributes:
        memory: bytes of memory (page cache, kernel memory and tmpfs pages included); no swap.
        processes: processes and threads at once (``pids.max``).
        cpu_cores: CPU bandwidth in cores (``cpu.max`` quota / period; 1.0 = one core's time).
        cpus: the cores the run may use (the cpuset); its processes cannot leave them.
    """

    memory: int
    processes: int
    cpu_cores: float
    cpus: tuple[int, ...]

    def __post_init__(self) -> None:
        require_positive(self, ("memory", "processes", "cpu_cores"))
        if not self.cpus or any(int(c) < 0 for c in self.cpus):
            raise ValueError(f"cpus must name at least one core, got {self.cpus!r}")


def _mounts() -> list[tuple[str, str, set[str]]]:
    """(mount point, fstype, options) of the cgroup file systems mounted here."""
    found = []
    with open("/proc/self/mounts", encoding="utf-8") as f:
        for line in f:
            parts = line.split()
            if len(parts) >= 4 and parts[2] in ("cgroup", "cgroup2"):
                found.append((parts[1].replace("\\040", " "), parts[2], set(parts[3].split(","))))
    return found


def _own_groups() -> dict[str, str]:
    """This process's group per v1 controller, and ``""`` → its v2 group (/proc/self/cgroup)."""
    groups = {}
    with open("/proc/self/cgroup", encoding="utf-8") as f:
        for line in f:
            _, controllers, path = line.rstrip("\n").split(":", 2)
            for name in controllers.split(",") if controllers else [""]:
                groups[name] = path
    return groups


def _cpus(text: str) -> set[int]:
    """``"0-3,6"`` → {0, 1, 2, 3, 6}."""
    cpus: set[int] = set()
    for part in text.strip().split(","):
        if part:
            low, _, high = part.partition("-")
            cpus.update(range(int(low), int(high or low) + 1))
    return cpus


def join(procs_files: list[str]) -> None:
    """This process (and all it starts from now on) joins a run's group: its pid into each
    of :attr:`RunCgroup.procs_files`."""
    pid = str(os.getpid())
    for path in procs_files:
        _write(Path(path), pid)


def _write(path: Path, value: str) -> None:
    fd = os.open(path, os.O_WRONLY)
    try:
        os.write(fd, value.encode())
    finally:
        os.close(fd)


def _layout() -> tuple[int, dict[str, Path]]:
    """(version, controller → the parent folder a run's group goes under). CgroupUnavailable otherwise."""
    if os.geteuid() != 0:
        raise CgroupUnavailable("creating a cgroup per run needs root")
    mounts = _mounts()
    for point, fstype, _ in mounts:
        if fstype == "cgroup2" and Path(point) == CGROUP_ROOT:
            try:
                available = set((CGROUP_ROOT / "cgroup.controllers").read_text().split())
            except OSError:
                available = set()
            if set(REQUIRED) <= available:
                return 2, {c: CGROUP_ROOT / "swarmdeck" for c in (*REQUIRED, *OPTIONAL) if c in available}
    own = _own_groups()
    parents = {}
    for point, fstype, options in mounts:
        if fstype != "cgroup":
            continue
        for controller in (*REQUIRED, *OPTIONAL, ACCOUNTING_V1):
            if controller in options and controller not in parents and controller in own:
                parents[controller] = Path(point) / own[controller].lstrip("/")
    missing = [c for c in REQUIRED if c not in parents]
    if missing:
        raise CgroupUnavailable(f"no cgroup {' or '.join(missing)} controller is mounted here "
                                f"(cgroup v2 at {CGROUP_ROOT} with memory and pids, or v1 hierarchies)")
    return 1, parents


def version() -> int | None:
    """The cgroup version a run's group would use here (2 or 1), None when none can be made (not root, no
    controllers)."""
    try:
        return _layout()[0]
    except CgroupUnavailable:
        return None


def probe() -> str | None:
    """None when a run's cgroup can be created here (tries one), else why not."""
    try:
        group = create(CgroupLimits(memory=64 << 20, processes=4, cpu_cores=1.0,
                                    cpus=tuple(sorted(os.sched_getaffinity(0)))), "probe")
    except CgroupUnavailable as exc:
        return str(exc)
    group.remove()
    return None


class RunCgroup:
    """One run's group (one folder per hierarchy in v1, one in v2). Made by :func:`create`."""

    def __init__(self, version: int, folders: dict[str, Path], limits: CgroupLimits, missing: tuple[str, ...]) -> None:
        self.version, self.folders, self.limits, self.missing = version, folders, limits, missing
        self._clock: tuple[int, int] | None = None  # cpu_time_s's open file (format, fd)

    @property
    def procs_files(self) -> list[str]:
        """The files a process writes its pid to, to join the group (every hierarchy's)."""
        return sorted({str(f / "cgroup.procs") for f in self.folders.values()})

    def pids(self) -> list[int]:
        """Processes in the group now."""
        found: set[int] = set()
        for path in self.procs_files:
            try:
                found |= {int(p) for p in Path(path).read_text().split()}
            except (OSError, ValueError):
                continue
        return sorted(found)

    def _read(self, controller: str, name: str) -> str:
        try:
            return (self.folders[controller] / name).read_text()
        except (OSError, KeyError):
            return ""

    def _counter(self, controller: str, name: str, key: str) -> int:
        for line in self._read(controller, name).splitlines():
            parts = line.split()
            if len(parts) == 2 and parts[0] == key and parts[1].isdigit():
                return int(parts[1])
        return 0

    def oom_kills(self) -> int:
        """Processes of the run the kernel killed for exceeding the memory limit."""
        if self.version == 2:
            return self._counter("memory", "memory.events", "oom_kill")
        return self._counter("memory", "memory.oom_control", "oom_kill")

    def memory_peak(self) -> int:
        """Most memory the run held at once, bytes (0 where the kernel does not say)."""
        text = self._read("memory", "memory.peak" if self.version == 2 else "memory.max_usage_in_bytes").strip()
        return int(text) if text.isdigit() else 0

    def cpu_time_s(self) -> float | None:
        """CPU time (user + system) all the run's processes have used so far, s, as the kernel accounts it
        (v2 ``cpu.stat`` usage_usec, v1 ``cpuacct.usage``); None where this group cannot tell.

        Read once per tick by the sandbox's loop: the file is opened once and re-read with ``pread`` (a tenth
        of the cost of opening it each time on this VM, bench/RESULTS.md "sandbox per tick"); closed by
        :meth:`remove`."""
        if self._clock is None:
            self._clock = self._open_clock()
        kind, fd = self._clock
        if fd < 0:
            return None
        try:
            text = os.pread(fd, 4096, 0).decode("ascii", "replace")
        except OSError:
            return None
        if kind == 2:
            for line in text.splitlines():
                parts = line.split()
                if len(parts) == 2 and parts[0] == "usage_usec" and parts[1].isdigit():
                    return int(parts[1]) * 1e-6
            return None
        text = text.strip()
        return int(text) * 1e-9 if text.isdigit() else None

    def _open_clock(self) -> tuple[int, int]:
        """(2 or 1: the format, fd of the CPU-time file, or −1 where there is none)."""
        if self.version == 2:
            candidates = [(2, folder / "cpu.stat") for folder in list(self.folders.values())[:1]]
        else:  # v1: its own hierarchy, or mounted together with cpu
            candidates = [(1, self.folders[c] / "cpuacct.usage") for c in (ACCOUNTING_V1, "cpu") if c in self.folders]
        for kind, path in candidates:
            try:
                fd = os.open(path, os.O_RDONLY | os.O_CLOEXEC)
            except OSError:
                continue
            if kind == 2 or os.pread(fd, 64, 0).strip().isdigit():
                return kind, fd
            os.close(fd)
        return 0, -1

    def _close_clock(self) -> None:
        clock, self._clock = self._clock, None
        if clock is not None and clock[1] >= 0:
            os.close(clock[1])

    def pids_refused(self) -> int:
        """Forks refused because the run had ``processes`` processes already."""
        return self._counter("pids", "pids.events", "max")

    def kill(self, timeout: float = 10.0) -> list[int]:
        """SIGKILL every process of the group until none is left (or ``timeout`` s); the survivors."""
        deadline = time.monotonic() + timeout
        if self.version == 2 and "memory" in self.folders:
            try:
                _write(self.folders["memory"] / "cgroup.kill", "1")
            except OSError:
                pass
        return kill_until_gone(self.pids, max(0.0, deadline - time.monotonic()), pause=0.005)

    def remove(self, timeout: float = 10.0) -> str | None:
        """Kill what is left in the group and delete it; None, or what could not be removed."""
        self._close_clock()
        survivors = self.kill(timeout)
        problems = [f"processes {survivors} survived"] if survivors else []
        deadline = time.monotonic() + timeout
        for folder in sorted(set(self.folders.values()), reverse=True):
            while True:
                try:
                    folder.rmdir()
                    break
                except FileNotFoundError:
                    break
                except OSError as exc:  # EBUSY while the last tasks are being reaped
                    if time.monotonic() > deadline:
                        problems.append(f"{folder}: {exc.strerror}")
                        break
                    time.sleep(0.001)
        return "; ".join(problems) or None


def _enable(folder: Path, controller: str) -> None:
    """v2: let ``folder``'s children use ``controller`` (enabled in every ancestor's subtree_control first)."""
    chain = [p for p in [folder, *folder.parents] if p == CGROUP_ROOT or p.is_relative_to(CGROUP_ROOT)][::-1]
    for parent in chain:
        parent.mkdir(exist_ok=True)
        if controller not in (parent / "cgroup.subtree_control").read_text().split():
            _write(parent / "cgroup.subtree_control", f"+{controller}")


STALE_S = 600.0
"""A run's group older than this (s) and empty is a leftover of a process that died mid-run."""


def sweep(min_age_s: float = STALE_S) -> list[Path]:
    """Remove the empty run groups older than ``min_age_s`` (left by a swarmdeck that was killed
    mid-run; the kernel refuses to remove a group that holds a process); the folders removed."""
    try:
        version, parents = _layout()
    except CgroupUnavailable:
        return []
    pattern = "run-*" if version == 2 else "swarmdeck-run-*"
    removed = []
    now = time.time()
    for parent in set(parents.values()):
        for folder in parent.glob(pattern):
            try:
                if now - folder.stat().st_mtime > min_age_s:
                    folder.rmdir()
                    removed.append(folder)
            except OSError:
                continue
    return removed


def create(limits: CgroupLimits, name: str | None = None) -> RunCgroup:
    """A new group for one run with ``limits`` applied, empty (a process joins by writing its pid
    to each of :attr:`RunCgroup.procs_files`). CgroupUnavailable when it cannot be made here.

    ``memory`` and ``pids`` must work; ``cpu`` or ``cpuset`` that cannot be enabled or set
    (e.g. v2's ``cpu`` with real-time tasks on the host) are left out and named in
    :attr:`RunCgroup.missing`.
    """
    version, parents = _layout()
    label = f"run-{name or os.getpid()}-{secrets.token_hex(4)}"
    folders: dict[str, Path] = {}
    missing = [c for c in OPTIONAL if c not in parents]
    try:
        accounting = (ACCOUNTING_V1,) if version == 1 and ACCOUNTING_V1 in parents else ()
        for controller in (*REQUIRED, *(c for c in OPTIONAL if c in parents), *accounting):
            try:
                if version == 2:
                    _enable(parents[controller], controller)
                    folder = parents[controller] / label
                    folder.mkdir(exist_ok=True)
                else:
                    folder = parents[controller] / f"swarmdeck-{label}"
                    folder.mkdir()
                folders[controller] = folder
                _apply(version, controller, folder, parents[controller], limits)
            except OSError:
                if controller in REQUIRED:
                    raise
                if controller == ACCOUNTING_V1:
                    folders.pop(controller, None)
                    continue
                missing.append(controller)
                if version == 1 and controller in folders:
                    folders.pop(controller).rmdir()
                folders.pop(controller, None)
    except OSError as exc:
        RunCgroup(version, folders, limits, ()).remove(timeout=1.0)
        raise CgroupUnavailable(f"cannot create the run's cgroup (v{version}): {exc}") from exc
    return RunCgroup(version, folders, limits, tuple(sorted(missing)))


def _apply(version: int, controller: str, folder: Path, parent: Path, limits: CgroupLimits) -> None:
    """Set ``controller``'s limits on the run's ``folder`` (``parent``: the folder it was made in)."""
    if controller == "memory":
        if version == 2:
            _write(folder / "memory.max", str(limits.memory))
            if (folder / "memory.swap.max").exists():
                _write(folder / "memory.swap.max", "0")
            _write(folder / "memory.oom.group", "1")
        else:
            _write(folder / "memory.limit_in_bytes", str(limits.memory))
            if (folder / "memory.memsw.limit_in_bytes").exists():  # swap accounting on: no swap either
                _write(folder / "memory.memsw.limit_in_bytes", str(limits.memory))
    elif controller == "pids":
        _write(folder / "pids.max", str(limits.processes))
    elif controller == "cpu":
        quota = max(1000, int(round(limits.cpu_cores * CPU_PERIOD_US)))
        if version == 2:
            _write(folder / "cpu.max", f"{quota} {CPU_PERIOD_US}")
        else:
            _write(folder / "cpu.cfs_period_us", str(CPU_PERIOD_US))
            _write(folder / "cpu.cfs_quota_us", str(quota))
    elif controller == "cpuset":
        allowed = _cpus((parent / ("cpuset.cpus.effective" if version == 2 else "cpuset.cpus")).read_text())
        _write(folder / "cpuset.cpus", ",".join(map(str, sorted(set(limits.cpus) & allowed) or sorted(allowed))))
        if version == 1:  # v1 starts a group with no memory nodes: none of its tasks could run
            _write(folder / "cpuset.mems", (parent / "cpuset.mems").read_text().strip())


class OomGuard:
    """Ends the whole run the moment the kernel OOM-kills any of its processes.

    cgroup v2 does this itself (``memory.oom.group``); v1 kills one process only, so a
    thread polls the group's OOM counter every ``interval`` s (one small file read) and
    kills everything in the group when it moves. Use as a context manager around the run.
    """

    def __init__(self, group: RunCgroup, interval: float = 0.05) -> None:
        self.group, self.interval = group, interval
        self._service = ServiceThread(self._run, "swarmdeck-oom-guard", join_timeout=None)

    def _run(self) -> None:
        while not self._service.wait(self.interval):
            if self.group.oom_kills():
                self.group.kill(timeout=2.0)
                return

    def __enter__(self) -> OomGuard:
        if self.group.version == 1:
            self._service.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._service.stop()
