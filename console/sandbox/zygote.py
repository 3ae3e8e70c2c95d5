"""A fork server for sandboxed scripts: Python, numpy and swarmdeck loaded once, a fresh jail per script.

Starting a Python process that imports numpy and swarmdeck costs about 0.15 s
of CPU, 8 % of a 20-robot, 60 s run: too much to pay per run. A
:class:`ForkServer` starts one such process (the *zygote*, this module's
``main``) per worker process; for each run it forks, and the fork builds a new
jail with :mod:`swarmdeck.console.sandbox.namespaces` (new mount, network, pid, ipc
and uts namespaces, a read-only root of its own) before the child's code runs.
The zygote never runs user code and never receives any — only paths, limits and
the run's pipe ends — so no script can see another's state: every script starts
from the same freshly loaded, untouched process image (random generators are
seeded anew in each fork).

The zygote is trusted code, started by swarmdeck with a clean environment; it
ends when its control socket closes (the worker process ended), killing the
runs it started. Requests over the socket (a ``SOCK_SEQPACKET`` pair; msgpack
maps, the pipe ends passed as file descriptors)::

    {"root": dir, "binds": [["ro"|"rw", path], ...], "symlinks": [[target, link], ...],
     "scratch": [path, tmpfs options] | None, "cgroup": [cgroup.procs file, ...], "keyring": bool}
        + fds (to_child_r, from_child_w, log_w, status_w)  ->  {"pid": A} | {"error": str}

Process A joins the cgroup (its pid into each file) and, with ``keyring``, a fresh
anonymous session keyring, before it builds the jail; the script's process loads the
seccomp filter the zygote built once (:func:`swarmdeck.console.sandbox.seccomp.filter_program`)
when its ``start`` message asks it to.

The run's status pipe gets one msgpack map when the jail's init ends:
``{"code": exit code of the script's process (128 + n when killed by signal n),
"cpu_s": CPU seconds of the jail's processes (the script's included)}`` or
``{"error": why the jail could not be built}``.
"""
from __future__ import annotations

import fcntl
import functools
import os
import select
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import msgspec

from swarmdeck.console.sandbox.cgroups import join as join_cgroup
from swarmdeck.console.sandbox.keyrings import join_session_keyring
from swarmdeck.console.sandbox.namespaces import (
    PR_SET_PDEATHSIG,
    build_root,
    enter_root,
    prctl,
    probe_in_child,
    unshare_all,
)
from swarmdeck.core.errors import SwarmdeckError

CHILD_ENV = {"PATH": "/usr/bin:/bin", "LANG": "C.UTF-8", "PYTHONHASHSEED": "0", "PYTHONDONTWRITEBYTECODE": "1",
             "PYTHONUNBUFFERED": "1", "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
_MAX_MESSAGE = 1 << 16


class ForkServerError(RuntimeError, SwarmdeckError):
    """The fork server could not start or stopped answering."""


class ForkServer:
    """The client side: starts the zygote and asks it for jailed children (thread-safe).

    ``unavailable``: None when this machine can build the jail, else the reason (the zygote
    tries it once when it starts). ``startup_cpu_s``: the zygote's CPU time to load and probe.
    """

    def __init__(self, boot_s: float = 120.0) -> None:
        ours, theirs = socket.socketpair(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        try:
            self.proc = subprocess.Popen(
                [sys.executable, "-s", "-m", "swarmdeck.console.sandbox.zygote", str(theirs.fileno())],
                pass_fds=(theirs.fileno(),), env=CHILD_ENV, cwd="/", stdin=subprocess.DEVNULL,
                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
        finally:
            theirs.close()
        self.sock = ours
        self.lock = threading.Lock()
        hello = self._receive(boot_s, "start")
        self.unavailable: str | None = hello.get("error")
        self.startup_cpu_s = float(hello.get("cpu_s", 0.0))

    def _receive(self, timeout: float, what: str) -> dict[str, Any]:
        ready, _, _ = select.select([self.sock], [], [], timeout)
        data = self.sock.recv(_MAX_MESSAGE) if ready else None
        if not data:
            self.close()
            raise ForkServerError(f"the sandbox's fork server did not {what}" + ("" if ready else f" within {timeout:g} s"))
        return msgspec.msgpack.decode(data)

    @property
    def alive(self) -> bool:
        return self.proc.poll() is None and self.sock.fileno() >= 0

    def spawn(self, root: Path, binds: list[tuple[str, Path]], symlinks: list[tuple[str, Path]],
              fds: tuple[int, int, int, int], *, scratch: tuple[Path, str] | None = None,
              cgroup: Sequence[str] = (), keyring: bool = True) -> int:
        """Fork a jailed child wired to ``fds`` (to_child_r, from_child_w, log_w, status_w); its pid (process A).

        ``scratch``: (path, tmpfs options) of the run's scratch tmpfs; ``cgroup``: the run's
        ``cgroup.procs`` files; ``keyring``: a fresh session keyring (see the module docstring).
        """
        request = {"root": str(root), "binds": [[k, str(p)] for k, p in binds],
                   "symlinks": [[t, str(p)] for t, p in symlinks],
                   "scratch": None if scratch is None else [str(scratch[0]), scratch[1]],
                   "cgroup": list(cgroup), "keyring": bool(keyring)}
        with self.lock:
            try:
                socket.send_fds(self.sock, [msgspec.msgpack.encode(request)], list(fds))
            except OSError as exc:
                self.close()
                raise ForkServerError(f"the sandbox's fork server is gone: {exc}") from exc
            reply = self._receive(30.0, "answer")
        if "pid" not in reply:
            raise ForkServerError(f"the sandbox's fork server could not start the run: {reply.get('error')}")
        return int(reply["pid"])

    def cpu_s(self) -> float:
        """The zygote's CPU time so far, s (its start-up and the forks)."""
        try:
            fields = Path(f"/proc/{self.proc.pid}/stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            return 0.0
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")

    def close(self) -> None:
        """End the zygote (and every run it started)."""
        try:
            self.sock.close()
        except OSError:
            pass
        try:
            self.proc.wait(timeout=5)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()


@functools.lru_cache(maxsize=4)
def _server_of(pid: int) -> ForkServer:
    from swarmdeck.console.sandbox.cgroups import sweep

    sweep()  # once per worker process: the empty run groups a killed predecessor left behind
    return ForkServer()


_shared_lock = threading.Lock()


def shared_fork_server() -> ForkServer:
    """This process's fork server, started on first use (again if it died); one per worker process."""
    with _shared_lock:
        server = _server_of(os.getpid())
        if not server.alive:
            _server_of.cache_clear()
            server = _server_of(os.getpid())
        return server


# ---------------------------------------------------------------------------- the zygote's side
def _send_status(fd: int, status: dict[str, Any]) -> None:
    try:
        os.write(fd, msgspec.msgpack.encode(status))
    except OSError:
        pass


def _keep_only(fds: dict[int, int]) -> None:
    """Make the file descriptors ``fds`` (target → source) the only open ones besides 0-2."""
    moved = {target: fcntl.fcntl(source, fcntl.F_DUPFD, 64) for target, source in fds.items()}  # above every target first
    for target, temporary in moved.items():
        os.dup2(temporary, target, inheritable=True)
    os.closerange(max(fds, default=2) + 1, os.sysconf("SC_OPEN_MAX"))
    for fd in range(3, max(fds, default=2) + 1):
        if fd not in fds:
            try:
                os.close(fd)
            except OSError:
                pass


def _exit_code(status: int) -> int:
    code = os.waitstatus_to_exitcode(status)
    return 128 - code if code < 0 else code  # killed by signal n: 128 + n, as bwrap reports it


def _run_c() -> None:
    """The script's process (pid 2): stdin /dev/null, stdout+stderr the log, the pipes at fds 3 and 4."""
    code = 1
    try:
        prctl(PR_SET_PDEATHSIG, signal.SIGKILL)
        null = os.open("/dev/null", os.O_RDONLY)
        os.dup2(null, 0)
        os.close(null)
        import numpy as np

        np.random.seed()  # every fork starts from the zygote's image: fresh entropy for the script's generators
        from swarmdeck.console.sandbox.child import main

        code = main(["3", "4"])
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else 1
    except BaseException:  # noqa: BLE001 - the script's process ends; the parent reads the log
        import traceback

        traceback.print_exc()
    finally:
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except (OSError, ValueError):
                pass
        os._exit(code)


def _run_b(root: Path) -> None:
    """The jail's init (pid 1 of the new pid namespace): enter the new root, fork the script, reap."""
    try:
        prctl(PR_SET_PDEATHSIG, signal.SIGKILL)
        enter_root(root)
        script = os.fork()
        if script == 0:
            _run_c()
        for fd in (0, 3, 4):
            os.close(fd)
        os.dup2(os.open("/dev/null", os.O_WRONLY), 1)
        os.dup2(1, 2)
        while True:
            pid, status = os.waitpid(-1, 0)
            if pid == script:
                os._exit(_exit_code(status))
    except BaseException:  # noqa: BLE001
        os._exit(125)


def _run_a(request: dict[str, Any], fds: list[int]) -> None:
    """Process A (host side): new namespaces and root, then the jail's init; reports how it ended."""
    status_fd = 5
    try:
        os.setsid()
        prctl(PR_SET_PDEATHSIG, signal.SIGKILL)
        _keep_only({3: fds[0], 4: fds[1], 1: fds[2], 2: fds[2], 5: fds[3]})
        root = Path(request["root"])
        try:
            join_cgroup(request.get("cgroup") or [])
            if request.get("keyring"):
                join_session_keyring()
            unshare_all()
            scratch = request.get("scratch")
            build_root(root, [(k, Path(p)) for k, p in request["binds"]],
                       [(t, Path(p)) for t, p in request["symlinks"]],
                       None if scratch is None else (Path(scratch[0]), str(scratch[1])))
        except OSError as exc:
            _send_status(status_fd, {"error": f"the jail could not be built: {exc}"})
            os._exit(0)
        init = os.fork()
        if init == 0:
            os.close(status_fd)
            _run_b(root)
        for fd in (1, 2, 3, 4):
            os.close(fd)
        _, status = os.waitpid(init, 0)
        import resource

        me, below = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = me.ru_utime + me.ru_stime + below.ru_utime + below.ru_stime
        _send_status(status_fd, {"code": _exit_code(status), "cpu_s": cpu})
    finally:
        os._exit(0)


def main(argv: list[str]) -> int:
    started = time.process_time()
    sock = socket.socket(fileno=int(argv[0]))
    import numpy as np  # loaded once here, shared by every run's fork

    import swarmdeck.console.sandbox.child  # noqa: F401

    np.random.seed()  # the first seeding loads its machinery (about 20 ms): once here, not in every run
    np.random.default_rng()
    from swarmdeck.console.sandbox.seccomp import SeccompUnavailable, filter_program

    try:
        filter_program()  # built once here; every run's script process loads this copy
    except SeccompUnavailable:
        pass  # the trusted side probes it and refuses hardened runs (the message says why)

    import gc

    gc.freeze()  # the loaded objects stay out of every fork's garbage collections: no copy-on-write of them
    error = probe_in_child()
    sock.send(msgspec.msgpack.encode({"error": error, "cpu_s": time.process_time() - started}))
    live: set[int] = set()
    while True:
        for pid in list(live):
            try:
                if os.waitpid(pid, os.WNOHANG)[0]:
                    live.discard(pid)
            except ChildProcessError:
                live.discard(pid)
        try:
            data, fds, _, _ = socket.recv_fds(sock, _MAX_MESSAGE, 8)
        except OSError:
            break
        if not data:
            break
        try:
            if len(fds) != 4 or error is not None:
                raise OSError(error or f"expected 4 file descriptors, got {len(fds)}")
            request = msgspec.msgpack.decode(data)
            pid = os.fork()
            if pid == 0:
                sock.close()
                _run_a(request, fds)
            live.add(pid)
            reply: dict[str, Any] = {"pid": pid}
        except (OSError, ValueError, msgspec.DecodeError) as exc:
            reply = {"error": str(exc)}
        finally:
            for fd in fds:
                os.close(fd)
        sock.send(msgspec.msgpack.encode(reply))
    for pid in live:
        try:
            os.killpg(pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
    for pid in live:
        try:
            os.waitpid(pid, 0)
        except ChildProcessError:
            pass
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
