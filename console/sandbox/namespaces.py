"""The ``unshare`` jail: Linux namespaces built with the kernel's own calls (unshare(2), mount(2), pivot_root(2)).

What ``unshare(1)`` does on the command line, done inside a freshly forked
process so that a pre-imported fork server (:mod:`swarmdeck.console.sandbox.zygote`)
can start each sandboxed script in a jail of its own without starting Python
again. Per run, three processes:

* **A** (host pid namespace): :func:`unshare_all` — new mount, network, ipc, uts
  and pid namespaces (and a user namespace mapping our uid to 0 when not root) —
  then :func:`build_root`: a private tmpfs root holding read-only bind mounts of
  what Python and swarmdeck need, the script's folder read-only, the scratch
  folder (a size- and inode-limited tmpfs of its own), and /dev's null, zero, full,
  random, urandom. Before that, A joins the run's cgroup and a fresh session keyring. A waits for B
  and reports its exit status and the CPU time of everything below it.
* **B** (pid 1 of the new pid namespace, the jail's init): :func:`enter_root` —
  /proc of the new pid namespace, ``pivot_root`` into the new root, the old root
  detached, the root remounted read-only — then it forks C and reaps orphans
  until C ends; when B ends, the kernel kills everything left in the namespace.
* **C** (pid 2): the script (resource limits, the uid drop and the seccomp filter are the
  child's own, see :mod:`swarmdeck.console.sandbox.child`).

The network namespace has only a loopback that is down: nothing, not even the
host's 127.0.0.1, is reachable. Needs root (or unprivileged user namespaces).
"""
from __future__ import annotations

import ctypes
import functools
import os
import platform
import signal
from pathlib import Path

CLONE_NEWNS = 0x00020000
CLONE_NEWUTS = 0x04000000
CLONE_NEWIPC = 0x08000000
CLONE_NEWUSER = 0x10000000
CLONE_NEWPID = 0x20000000
CLONE_NEWNET = 0x40000000
MS_RDONLY, MS_NOSUID, MS_NODEV, MS_NOEXEC = 1, 2, 4, 8
MS_REMOUNT, MS_BIND, MS_REC, MS_PRIVATE = 32, 4096, 16384, 1 << 18
MS_NOATIME, MS_NODIRATIME, MS_RELATIME = 1024, 2048, 1 << 21
MNT_DETACH = 2
PR_SET_PDEATHSIG, PR_SET_NO_NEW_PRIVS = 1, 38
_SYS_PIVOT_ROOT = {"x86_64": 155, "aarch64": 41, "arm64": 41}
DEVICES = ("null", "zero", "full", "random", "urandom")
# statvfs f_flag bits → the mount flags a read-only remount must keep (locked in a user namespace)
_KEEP = ((os.ST_NOSUID, MS_NOSUID), (os.ST_NODEV, MS_NODEV), (os.ST_NOEXEC, MS_NOEXEC),
         (os.ST_NOATIME, MS_NOATIME), (os.ST_NODIRATIME, MS_NODIRATIME), (os.ST_RELATIME, MS_RELATIME))


@functools.lru_cache(maxsize=1)
def _libc() -> ctypes.CDLL:
    return ctypes.CDLL(None, use_errno=True)


def warm() -> None:
    """Load libc through ctypes now (before a fork whose child mounts)."""
    _libc().mount, _libc().unshare  # noqa: B018 - resolving the symbols is the point


def _check(result: int, what: str) -> None:
    if result != 0:
        errno = ctypes.get_errno()
        raise OSError(errno, f"{what}: {os.strerror(errno)}")


def _mount(source: str | None, target: str | Path, fstype: str | None, flags: int, data: str | None = None) -> None:
    def enc(s: str | None) -> bytes | None:
        return None if s is None else os.fsencode(s)

    _check(_libc().mount(enc(source), enc(str(target)), enc(fstype), ctypes.c_ulong(flags), enc(data)),
           f"mount {source or ''} on {target}")


def prctl(option: int, value: int) -> None:
    _check(_libc().prctl(option, ctypes.c_ulong(value), ctypes.c_ulong(0), ctypes.c_ulong(0), ctypes.c_ulong(0)),
           f"prctl({option})")


def die_with_parent(parent_pid: int, sig: int = signal.SIGKILL) -> None:
    """This process gets ``sig`` when its parent ``parent_pid`` ends (``PR_SET_PDEATHSIG``), even by kill -9.

    If the parent already ended before the request took effect (this process was re-parented), the
    signal is raised now. Linux sends it when the parent *thread* that started this process ends: call
    it only in processes whose starting thread outlives them (a pool created and joined by one thread).
    """
    prctl(PR_SET_PDEATHSIG, int(sig))
    if os.getppid() != int(parent_pid):
        os.kill(os.getpid(), int(sig))


def unshare_all() -> None:
    """New mount, network, ipc, uts and pid namespaces for this process (pid: for its children);
    as non-root also a user namespace in which this process is root (uid map ``0 <uid> 1``)."""
    uid, gid = os.getuid(), os.getgid()
    userns = os.geteuid() != 0
    flags = CLONE_NEWNS | CLONE_NEWNET | CLONE_NEWIPC | CLONE_NEWUTS | CLONE_NEWPID | (CLONE_NEWUSER if userns else 0)
    _check(_libc().unshare(ctypes.c_int(flags)), "unshare")
    if userns:
        Path("/proc/self/setgroups").write_text("deny")
        Path("/proc/self/uid_map").write_text(f"0 {uid} 1")
        Path("/proc/self/gid_map").write_text(f"0 {gid} 1")


def _kept_flags(path: Path) -> int:
    f_flag = os.statvfs(path).f_flag
    return sum(ms for st, ms in _KEEP if f_flag & st)


def _bind(source: Path, target: Path, read_only: bool, extra: int = 0) -> None:
    _mount(str(source), target, None, MS_BIND)
    if read_only or extra:
        _mount(None, target, None, MS_BIND | MS_REMOUNT | (MS_RDONLY if read_only else 0) | extra | _kept_flags(source))


def scratch_options(size: int, inodes: int, uid: int | None) -> str:
    """tmpfs mount options of a run's scratch: at most ``size`` bytes and ``inodes`` files and
    folders, mode 0700, owned by ``uid`` (None: by whoever mounts it)."""
    owner = "" if uid is None else f",uid={int(uid)},gid={int(uid)}"
    return f"size={int(size)},nr_inodes={int(inodes)},mode=0700{owner}"


def mount_scratch(target: str | Path, options: str) -> None:
    """A fresh tmpfs (options from :func:`scratch_options`) at ``target``, no setuid files, no devices."""
    _mount("tmpfs", target, "tmpfs", MS_NOSUID | MS_NODEV, options)


def private_mounts() -> None:
    """A mount namespace of this process's own, nothing in it propagating to the host's."""
    _check(_libc().unshare(ctypes.c_int(CLONE_NEWNS)), "unshare(CLONE_NEWNS)")
    _mount(None, "/", None, MS_REC | MS_PRIVATE)


def build_root(root: Path, binds: list[tuple[str, Path]], symlinks: list[tuple[str, Path]],
               scratch: tuple[Path, str] | None = None) -> None:
    """In the new mount namespace: a tmpfs at ``root`` (an empty directory) holding ``binds``
    (``("ro" | "rw", absolute path)``, each at its own path), ``symlinks`` (target, link path),
    the /dev nodes of :data:`DEVICES` and, when ``scratch`` is ``(path, tmpfs options)``, a
    size- and inode-limited tmpfs at that path (:func:`scratch_options`). Run in process A,
    after :func:`unshare_all`."""
    os.umask(0o022)  # the mount points we make are traversable by the jail's uid whatever umask started us (the
    # portal runs with 077); this process only builds the jail
    _mount(None, "/", None, MS_REC | MS_PRIVATE)  # nothing we mount propagates to the host
    _mount("tmpfs", root, "tmpfs", MS_NOSUID | MS_NODEV, "mode=0755,size=1m")
    for target, link in symlinks:
        os.symlink(target, root / link.relative_to("/"))
    for kind, path in binds:
        inside = root / path.relative_to("/")
        inside.mkdir(parents=True, exist_ok=True)
        _bind(path, inside, read_only=kind == "ro")
    if scratch is not None:
        inside = root / Path(scratch[0]).relative_to("/")
        inside.mkdir(parents=True, exist_ok=True)
        mount_scratch(inside, scratch[1])
    (root / "dev").mkdir(exist_ok=True)
    for name in DEVICES:
        node = root / "dev" / name
        node.touch()
        _bind(Path("/dev") / name, node, read_only=False, extra=MS_NOSUID | MS_NOEXEC)
    (root / "proc").mkdir(exist_ok=True)


def enter_root(root: Path) -> None:
    """In process B (pid 1 of the new pid namespace): its /proc, ``pivot_root`` into ``root``, the
    old root detached (nothing of the host is reachable any more), the new root read-only."""
    _mount("proc", root / "proc", "proc", MS_NOSUID | MS_NODEV | MS_NOEXEC)
    os.chdir(root)
    number = _SYS_PIVOT_ROOT.get(platform.machine())
    if number is None:
        raise OSError(f"pivot_root: unknown system call number on {platform.machine()}")
    _check(_libc().syscall(ctypes.c_long(number), b".", b"."), "pivot_root")
    _check(_libc().umount2(b".", ctypes.c_int(MNT_DETACH)), "umount old root")
    os.chdir("/")
    _mount(None, "/", None, MS_REMOUNT | MS_RDONLY | MS_NOSUID | MS_NODEV)


def probe_in_child() -> str | None:
    """Try the whole jail in a throw-away forked process; None when it works, else the reason."""
    import tempfile

    root = Path(tempfile.mkdtemp(prefix="swarmdeck-probe-"))
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:  # pragma: no cover (the forked child)
        os.close(read)
        message = b""
        try:
            unshare_all()
            build_root(root, [("ro", Path("/usr").resolve())], [])
            inner = os.fork()
            if inner == 0:
                try:
                    enter_root(root)
                    os._exit(0)
                except BaseException:
                    os._exit(3)
            _, status = os.waitpid(inner, 0)
            if os.waitstatus_to_exitcode(status) != 0:
                message = b"entering the new root failed"
        except BaseException as exc:  # noqa: BLE001 - reported to the parent
            message = str(exc).encode(errors="replace")[:300] or b"failed"
        os.write(write, message)
        os._exit(0)
    os.close(write)
    chunks = []
    while chunk := os.read(read, 4096):
        chunks.append(chunk)
    os.close(read)
    os.waitpid(pid, 0)
    try:
        root.rmdir()
    except OSError:
        pass
    text = b"".join(chunks).decode(errors="replace")
    return text or None
