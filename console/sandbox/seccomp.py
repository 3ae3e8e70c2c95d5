"""The sandbox's seccomp filter: system calls a user's script may never make, built with libseccomp.

One BPF program for both jails (:mod:`swarmdeck.console.sandbox.confinement`): built once
by :func:`filter_program` with Debian's ``libseccomp.so.2`` through :mod:`ctypes`
(``seccomp_init`` / ``seccomp_rule_add_array`` / ``seccomp_export_bpf``: libseccomp
writes the BPF, including the architecture check), then

* loaded by bubblewrap (``--seccomp FD``) right before it starts the child's Python, or
* loaded by the ``unshare`` jail's script process itself (:func:`install`, the
  ``seccomp(2)`` call with ``SECCOMP_FILTER_FLAG_TSYNC``) after its mounts, limits and uid
  drop, before any user code.

Everything is allowed except (each answered ``EPERM`` unless said otherwise):

* kernel keyrings: ``keyctl``, ``add_key``, ``request_key`` (keyrings are not namespaced);
* new namespaces and joining others: ``unshare``, ``setns``, ``clone`` with any
  ``CLONE_NEW*`` flag in its flags argument, and ``clone3`` — whose flags live in memory a
  filter cannot read — answered ``ENOSYS`` so that the C library falls back to ``clone``;
* mounts: ``mount``, ``umount2``, ``pivot_root``, ``chroot``, ``fsopen``, ``fsconfig``,
  ``fsmount``, ``fspick``, ``open_tree``, ``move_mount``, ``mount_setattr``;
* kernel attack surface with a long record of privilege escalations: ``io_uring_setup`` /
  ``_enter`` / ``_register``, ``bpf``, ``perf_event_open``, ``userfaultfd``,
  ``fanotify_init``, ``open_by_handle_at``, ``name_to_handle_at``;
* other processes' memory: ``ptrace``, ``process_vm_readv`` / ``_writev``, ``kcmp``,
  ``pidfd_getfd``, ``process_madvise``;
* the machine: ``kexec_load``, ``kexec_file_load``, ``init_module``, ``finit_module``,
  ``delete_module``, ``reboot``, ``swapon``, ``swapoff``, ``acct``, ``quotactl``,
  ``sethostname``, ``setdomainname``, ``syslog``, ``settimeofday``, ``clock_settime``,
  ``clock_adjtime``, ``adjtimex``, ``iopl``, ``ioperm``, ``vhangup``, ``uselib``,
  ``lookup_dcookie``, ``personality`` (but the query ``personality(0xffffffff)``), and
  ``ioctl`` ``TIOCSTI`` / ``TIOCLINUX`` (typing into a terminal).

System calls of another architecture (i386 through ``int 0x80``, x32) kill the process.
Names libseccomp does not know on this architecture are skipped.
"""
from __future__ import annotations

import ctypes
import ctypes.util
import errno as errnos
import functools
import os
import platform

from swarmdeck.core.errors import SwarmdeckError

# libseccomp's constants (seccomp.h, libseccomp 2.5)
SCMP_ACT_KILL_PROCESS = 0x80000000
SCMP_ACT_ALLOW = 0x7FFF0000
_SCMP_ACT_ERRNO = 0x00050000
SCMP_CMP_NE, SCMP_CMP_MASKED_EQ = 1, 7
SCMP_FLTATR_ACT_BADARCH, SCMP_FLTATR_CTL_NNP = 2, 3
_SYS_SECCOMP = {"x86_64": 317, "aarch64": 277, "arm64": 277}
SECCOMP_SET_MODE_FILTER, SECCOMP_FILTER_FLAG_TSYNC = 1, 1
PR_SET_NO_NEW_PRIVS = 38

CLONE_NEW_FLAGS = {"CLONE_NEWNS": 0x00020000, "CLONE_NEWCGROUP": 0x02000000, "CLONE_NEWUTS": 0x04000000,
                   "CLONE_NEWIPC": 0x08000000, "CLONE_NEWUSER": 0x10000000, "CLONE_NEWPID": 0x20000000,
                   "CLONE_NEWNET": 0x40000000}
TIOCSTI, TIOCLINUX = 0x5412, 0x541C
PERSONALITY_QUERY = 0xFFFFFFFF

DENIED = (
    "keyctl", "add_key", "request_key",
    "unshare", "setns",
    "mount", "umount2", "pivot_root", "chroot", "fsopen", "fsconfig", "fsmount", "fspick", "open_tree", "move_mount",
    "mount_setattr",
    "io_uring_setup", "io_uring_enter", "io_uring_register", "bpf", "perf_event_open", "userfaultfd", "fanotify_init",
    "open_by_handle_at", "name_to_handle_at",
    "ptrace", "process_vm_readv", "process_vm_writev", "kcmp", "pidfd_getfd", "process_madvise",
    "kexec_load", "kexec_file_load", "init_module", "finit_module", "delete_module", "reboot", "swapon", "swapoff",
    "acct", "quotactl", "sethostname", "setdomainname", "syslog", "settimeofday", "clock_settime", "clock_adjtime",
    "adjtimex", "iopl", "ioperm", "vhangup", "uselib", "lookup_dcookie",
)
"""System calls refused outright (``EPERM``)."""


class SeccompUnavailable(RuntimeError, SwarmdeckError):
    """libseccomp cannot be loaded or cannot build the filter here (the message says why)."""


class _ArgCmp(ctypes.Structure):
    _fields_ = [("arg", ctypes.c_uint), ("op", ctypes.c_int), ("datum_a", ctypes.c_uint64),
                ("datum_b", ctypes.c_uint64)]


def errno_action(code: int) -> int:
    """libseccomp's ``SCMP_ACT_ERRNO(code)``: the call fails with ``code``."""
    return _SCMP_ACT_ERRNO | (int(code) & 0xFFFF)


@functools.lru_cache(maxsize=1)
def _lib() -> ctypes.CDLL:
    name = ctypes.util.find_library("seccomp") or "libseccomp.so.2"
    try:
        lib = ctypes.CDLL(name, use_errno=True)
    except OSError as exc:
        raise SeccompUnavailable(f"libseccomp is not installed (Debian: apt-get install libseccomp2): {exc}") from exc
    lib.seccomp_init.restype = ctypes.c_void_p
    lib.seccomp_init.argtypes = [ctypes.c_uint32]
    lib.seccomp_release.argtypes = [ctypes.c_void_p]
    lib.seccomp_attr_set.argtypes = [ctypes.c_void_p, ctypes.c_int, ctypes.c_uint32]
    lib.seccomp_syscall_resolve_name.argtypes = [ctypes.c_char_p]
    lib.seccomp_rule_add_array.argtypes = [ctypes.c_void_p, ctypes.c_uint32, ctypes.c_int, ctypes.c_uint,
                                           ctypes.POINTER(_ArgCmp)]
    lib.seccomp_export_bpf.argtypes = [ctypes.c_void_p, ctypes.c_int]
    return lib


def _rule(ctx: int, action: int, name: str, *conditions: tuple[int, int, int, int]) -> None:
    lib = _lib()
    number = lib.seccomp_syscall_resolve_name(name.encode())
    if number < 0:
        return  # not a system call of this architecture
    array = (_ArgCmp * max(1, len(conditions)))(*[_ArgCmp(*c) for c in conditions])
    rc = lib.seccomp_rule_add_array(ctypes.c_void_p(ctx), action, number, len(conditions), array)
    if rc < 0:
        raise SeccompUnavailable(f"libseccomp refused the rule for {name}: {os.strerror(-rc)}")


@functools.lru_cache(maxsize=1)
def filter_program() -> bytes:
    """The filter as a BPF program (``struct sock_filter`` array, 8 bytes an instruction), built once.

    SeccompUnavailable when libseccomp is missing or refuses a rule.
    """
    lib = _lib()
    ctx = lib.seccomp_init(SCMP_ACT_ALLOW)
    if not ctx:
        raise SeccompUnavailable("seccomp_init failed")
    try:
        for attr, value in ((SCMP_FLTATR_ACT_BADARCH, SCMP_ACT_KILL_PROCESS), (SCMP_FLTATR_CTL_NNP, 0)):
            rc = lib.seccomp_attr_set(ctypes.c_void_p(ctx), attr, value)
            if rc < 0:
                raise SeccompUnavailable(f"seccomp_attr_set({attr}) failed: {os.strerror(-rc)}")
        eperm = errno_action(errnos.EPERM)
        for name in DENIED:
            _rule(ctx, eperm, name)
        for flag in CLONE_NEW_FLAGS.values():
            _rule(ctx, eperm, "clone", (0, SCMP_CMP_MASKED_EQ, flag, flag))
        _rule(ctx, errno_action(errnos.ENOSYS), "clone3")
        for request in (TIOCSTI, TIOCLINUX):
            _rule(ctx, eperm, "ioctl", (1, SCMP_CMP_MASKED_EQ, 0xFFFFFFFF, request))
        _rule(ctx, eperm, "personality", (0, SCMP_CMP_NE, PERSONALITY_QUERY, 0))
        fd = os.memfd_create("swarmdeck-seccomp", 0)
        try:
            rc = lib.seccomp_export_bpf(ctypes.c_void_p(ctx), fd)
            if rc < 0:
                raise SeccompUnavailable(f"seccomp_export_bpf failed: {os.strerror(-rc)}")
            os.lseek(fd, 0, os.SEEK_SET)
            chunks = []
            while chunk := os.read(fd, 1 << 16):
                chunks.append(chunk)
        finally:
            os.close(fd)
    finally:
        lib.seccomp_release(ctypes.c_void_p(ctx))
    program = b"".join(chunks)
    if not program or len(program) % 8:
        raise SeccompUnavailable(f"libseccomp exported a malformed program ({len(program)} bytes)")
    return program


def probe() -> str | None:
    """None when the filter can be built here, else why not."""
    try:
        filter_program()
    except SeccompUnavailable as exc:
        return str(exc)
    if platform.machine() not in _SYS_SECCOMP:
        return f"seccomp(2): unknown system call number on {platform.machine()}"
    return None


class _SockFprog(ctypes.Structure):
    _fields_ = [("len", ctypes.c_ushort), ("filter", ctypes.c_void_p)]


def install(program: bytes) -> None:
    """Load ``program`` (from :func:`filter_program`) on every thread of this process, for good.

    Sets no_new_privs first (the kernel requires it of a process without CAP_SYS_ADMIN; it is
    the sandbox's rule anyway). OSError when the kernel refuses.
    """
    libc = ctypes.CDLL(None, use_errno=True)
    if libc.prctl(PR_SET_NO_NEW_PRIVS, ctypes.c_ulong(1), ctypes.c_ulong(0), ctypes.c_ulong(0), ctypes.c_ulong(0)):
        code = ctypes.get_errno()
        raise OSError(code, f"prctl(PR_SET_NO_NEW_PRIVS): {os.strerror(code)}")
    number = _SYS_SECCOMP.get(platform.machine())
    if number is None:
        raise OSError(errnos.ENOSYS, f"seccomp(2): unknown system call number on {platform.machine()}")
    buffer = ctypes.create_string_buffer(program, len(program))
    prog = _SockFprog(len(program) // 8, ctypes.cast(buffer, ctypes.c_void_p))
    if libc.syscall(ctypes.c_long(number), ctypes.c_uint(SECCOMP_SET_MODE_FILTER),
                    ctypes.c_uint(SECCOMP_FILTER_FLAG_TSYNC), ctypes.byref(prog)) != 0:
        code = ctypes.get_errno()
        raise OSError(code, f"seccomp(SECCOMP_SET_MODE_FILTER): {os.strerror(code)}")
