"""Kernel keyrings around a sandboxed run (REFERENCE.md §18: keyrings are not namespaced).

A child inherits its parent's session keyring across fork, exec and uid changes, so a
jailed script could read or plant keys in the keyring of whoever started swarmdeck.
Before any user code runs, the jail's first process joins a fresh anonymous session
keyring (:func:`join_session_keyring`); the seccomp filter then refuses ``keyctl``,
``add_key`` and ``request_key`` altogether (:mod:`swarmdeck.console.sandbox.seccomp`).
A run's uid is its own (:mod:`swarmdeck.console.sandbox.uids`); after the run the trusted
side empties that uid's user and user-session keyrings
(:func:`clear_user_keyrings`), which otherwise outlive every process of the uid.
"""
from __future__ import annotations

import ctypes
import functools
import os
import platform
from collections.abc import Callable

KEYCTL_GET_KEYRING_ID, KEYCTL_JOIN_SESSION_KEYRING, KEYCTL_CLEAR, KEYCTL_READ = 0, 1, 7, 11
KEY_SPEC_SESSION_KEYRING, KEY_SPEC_USER_KEYRING, KEY_SPEC_USER_SESSION_KEYRING = -3, -4, -5
_SYS_KEYCTL = {"x86_64": 250, "aarch64": 219, "arm64": 219}


@functools.lru_cache(maxsize=1)
def _syscall() -> Callable[..., int]:
    fn = ctypes.CDLL(None, use_errno=True).syscall
    fn.restype = ctypes.c_long
    return fn


def warm() -> None:
    """Resolve libc's ``syscall`` and this machine's architecture now (before a fork whose child calls
    :func:`keyctl`)."""
    _syscall()
    platform.machine()


def keyctl(operation: int, *args: int) -> int:
    """``keyctl(2)``: its result; OSError with the errno when it fails."""
    number = _SYS_KEYCTL.get(platform.machine())
    if number is None:
        raise OSError(38, f"keyctl: unknown system call number on {platform.machine()}")
    result = _syscall()(ctypes.c_long(number), ctypes.c_long(operation), *[ctypes.c_long(a) for a in args])
    if result < 0:
        code = ctypes.get_errno()
        raise OSError(code, f"keyctl({operation}): {os.strerror(code)}")
    return int(result)


def join_session_keyring() -> int:
    """This process (and what it starts) gets a fresh anonymous session keyring; its serial number."""
    return keyctl(KEYCTL_JOIN_SESSION_KEYRING, 0)


def uids_with_keys() -> set[int]:
    """The uids that own keys or keyrings now (``/proc/key-users``; all of them as root)."""
    try:
        with open("/proc/key-users", encoding="ascii") as f:
            return {int(line.split(":", 1)[0]) for line in f if ":" in line}
    except OSError:
        return set()


def clear_user_keyrings(uid: int) -> None:
    """Empty ``uid``'s user and user-session keyrings (as root; a no-op when the uid owns no key).

    A short-lived forked process takes the uid (the kernel resolves ``@u``/``@us`` from the
    caller's uid) and clears both: the keys they held lose their last link and are
    garbage-collected, so nothing a run left there reaches a later holder of the uid. (They are
    not invalidated: the kernel would then refuse every lookup of the uid's keyrings until its
    garbage collector ran.) OSError when it could not.
    """
    if uid not in uids_with_keys():
        return  # (looking a user keyring up creates it: do not, when there is nothing to clear)
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:  # pragma: no cover (the forked child)
        os.close(read)
        message = b""
        try:
            os.setgroups([])
            os.setresgid(uid, uid, uid)
            os.setresuid(uid, uid, uid)
            for spec in (KEY_SPEC_USER_SESSION_KEYRING, KEY_SPEC_USER_KEYRING):
                keyctl(KEYCTL_CLEAR, keyctl(KEYCTL_GET_KEYRING_ID, spec, 1))
        except BaseException as exc:  # noqa: BLE001 - reported to the parent
            message = str(exc).encode(errors="replace")[:300] or b"failed"
        os.write(write, message)
        os._exit(0)
    os.close(write)
    with os.fdopen(read, "rb") as f:
        message = f.read()
    os.waitpid(pid, 0)
    if message:
        raise OSError(f"could not clear the keyrings of uid {uid}: {message.decode(errors='replace')}")
