"""The trusted side of a sandboxed run: start the jailed child, exchange poses and commands per tick.

The user's script runs in :mod:`swarmdeck.console.sandbox.child`, inside a jail
chosen by :class:`~swarmdeck.console.sandbox.confinement.JailConfig`: by default
``unshare`` — a fresh set of Linux namespaces around a fork of the worker's
pre-imported fork server (:mod:`swarmdeck.console.sandbox.zygote`), no Python start-up
per run — else bubblewrap (a new Python per run); where neither works, untrusted
code is refused. This module owns the loop: each tick it sends the poses the
script may see (one binary frame) and waits — at most the per-tick budget — for
the script's nominal velocities (one binary frame), then hands them to the
:class:`Plant` (the simulator with the wheel limits and the safety filter, later
the real robots). A missed tick — no answer within the budget, or an answer
tagged with another tick's number (stale) — stops the robots for that tick and
still advances the plant (simulated time goes on), counted in ``overruns``;
``max_overruns`` such ticks in a row end the run, and the wall-time limit and a
cancel are checked after every plant step, so nothing the script answers keeps
a run from ending. Whatever the child does (dies,
hangs, floods its output, sends garbage), the run ends with a
:class:`SandboxOutcome` naming the reason, and the child and everything it
started are killed.

API (for the portal and other callers)::

    from swarmdeck.console.sandbox.bundle import ScriptBundle
    from swarmdeck.console.sandbox.run import run_sandboxed
    from swarmdeck.console.sandbox.verification import VerificationConfig, verify

    # one file, as before
    outcome = run_sandboxed("my_script.py", make_plant, n_robots=6, duration=30.0)
    # a folder (e.g. an extracted .zip): entry file relative to it, sibling modules importable
    outcome = run_sandboxed("upload_dir/", make_plant, entry="main.py", n_robots=6, duration=30.0)
    # files in memory (nothing of the upload touches a path of ours until the jail's own copy)
    bundle = ScriptBundle.from_files({"main.py": b"...", "lib/helpers.py": b"..."}, entry="main.py")
    outcome = run_sandboxed(bundle, make_plant, n_robots=6, duration=30.0)
    # verification takes the same three kinds of script
    report = verify([bundle], VerificationConfig(n_robots=6, duration=30.0))   # or verify(["dir/"], cfg, entry="main.py")

``make_plant(n, initial_poses_or_None) -> Plant`` builds the trusted side's robots
once the script asked for its Arena (raise ValueError to refuse it: the run ends
with ``ended_by == "arena"``). The files are copied into a fresh folder that the
jail binds read-only; the script's working directory is a private scratch tmpfs
(the only writable place, limited in bytes and files, gone with the jail). Bundle limits and the checks on
file names (relative paths only, no symlinks): :mod:`swarmdeck.console.sandbox.bundle`;
invalid bundles raise ValueError naming the problem. Where this machine cannot
confine code, :class:`~swarmdeck.console.sandbox.confinement.ConfinementUnavailable`
is raised unless ``trusted=True`` (or, for a missing cgroup, ``jail.allow_no_cgroup``).
Around every confined run the trusted side reserves the run's uid, creates its cgroup
and watches it for OOM kills, and afterwards removes the group, kills what is left of
the uid and clears its keyrings (see :mod:`swarmdeck.console.sandbox.confinement`).
"""
from __future__ import annotations

import contextlib
import inspect
import logging
import os
import select
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import msgspec
import numpy as np
from numpy.typing import NDArray

from swarmdeck.console.sandbox import cgroups, uids
from swarmdeck.console.sandbox import seccomp as seccomp_filter
from swarmdeck.console.sandbox.bundle import ScriptBundle
from swarmdeck.console.sandbox.confinement import (
    ConfinementUnavailable,
    JailConfig,
    SandboxLimits,
    bwrap_command,
    choose_jail,
    jail_layout,
    kill_all_of,
)
from swarmdeck.console.sandbox.keyrings import join_session_keyring
from swarmdeck.console.sandbox.keyrings import warm as warm_keyctl
from swarmdeck.console.sandbox.namespaces import mount_scratch, private_mounts, scratch_options
from swarmdeck.console.sandbox.namespaces import warm as warm_mounts
from swarmdeck.console.sandbox.network_link import network_config_from_message
from swarmdeck.console.sandbox.protocol import (
    COMMANDS,
    MESSAGE,
    FrameReader,
    ProtocolError,
    commands,
    decode,
    decode_draw,
    encode_poses,
    floats,
    network_traffic,
    write_frame,
)
from swarmdeck.console.sandbox.protocol import obstacles as script_obstacles
from swarmdeck.console.sandbox.script_env import ScriptEnv
from swarmdeck.console.sandbox.senses import leds_from_message, readings_message, sensing_from_message
from swarmdeck.console.sandbox.zygote import CHILD_ENV, ForkServerError, shared_fork_server
from swarmdeck.core.robot_models import DEFAULT_ROBOT_MODEL
from swarmdeck.devices.experiment_params import check_metrics


class Plant(Protocol):
    """What the trusted loop drives: the simulator (or robots) behind the wheel limits and the safety filter."""

    n: int

    def observe(self) -> tuple[float, NDArray[np.float64]]:
        """(time s, poses (N, 3)) the script may see now."""

    def apply(self, nominal: NDArray[np.float64] | None) -> None:
        """One tick with the script's nominal look-ahead velocities (N, 2), m/s (rows may be NaN: the
        plant stops those robots); None: the script missed the tick (stop)."""

    def finished(self) -> bool:
        """True when the run's declared duration is over."""


PlantFactory = Callable[[int, "NDArray[np.float64] | None"], Plant]


@dataclass
class SandboxOutcome:
    """How a sandboxed run ended.

    ``ended_by``: ``"script"`` (returned or exited), ``"duration"`` (declared duration over),
    ``"error"`` (the script raised or could not be loaded), ``"boot"`` (the child did not load
    within ``boot_s``), ``"startup"`` (no Arena within
    ``startup_s``), ``"overruns"`` (per-tick budget missed ``max_overruns`` times in a row),
    ``"wall"`` (wall-time limit), ``"crash"`` (the child died: a resource limit, a signal),
    ``"memory"`` (the run's processes together exceeded ``limits.memory``: the kernel killed them),
    ``"protocol"`` (the child sent something invalid), ``"arena"`` (the Arena it asked for was
    refused), ``"cancelled"``. ``error_line``: the reason in one line (None for clean ends).
    ``jail``: "unshare", "bwrap" or None (unconfined, ``trusted``). ``child_cpu_s``: CPU time of
    the sandboxed processes — measured by the jail's trusted process A with the ``unshare`` jail,
    else as the script's process reported it (informational, untrusted). ``uid``: the run's own uid
    (None when swarmdeck is not root or the run was unconfined). ``cgroup``: ``"v1"`` or ``"v2"``,
    the run's cgroup, or None when it ran without one (``unhardened`` says why).
    ``unhardened``: what of the hardening this run went without, one line each (empty normally).
    ``metrics``: the last values the script recorded (``swarmdeck.devices.record_metrics``; its own account).
    """

    ended_by: str = "script"
    error: str | None = None
    error_line: str | None = None
    n_robots: int | None = None
    ticks: int = 0
    overruns: int = 0
    child_cpu_s: float | None = None
    jail: str | None = None
    uid: int | None = None
    cgroup: str | None = None
    unhardened: list[str] = field(default_factory=list)
    log: str = ""
    log_bytes: int = 0
    plant: Any = field(default=None, repr=False)
    #: what the script reported with ``swarmdeck.devices.record_metrics`` (checked: names, finite numbers)
    metrics: dict[str, float] = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        return self.error_line is None


class _LogDrain(threading.Thread):
    """Reads the child's stdout+stderr (a pipe) to the end, keeping the first ``limit`` bytes (and handing each
    kept chunk to ``on_log`` as it comes: the portal's live log)."""

    def __init__(self, fd: int, limit: int, on_log: Callable[[bytes], None] | None = None) -> None:
        super().__init__(daemon=True)
        self.fd, self.limit, self.on_log = fd, limit, on_log
        self.kept = bytearray()
        self.total = 0

    def run(self) -> None:
        try:
            while True:
                try:
                    chunk = os.read(self.fd, 1 << 16)
                except OSError:
                    return
                if not chunk:
                    return
                self.total += len(chunk)
                room = self.limit - len(self.kept)
                if room > 0:
                    self.kept += chunk[:room]
                    if self.on_log is not None:
                        try:
                            self.on_log(bytes(chunk[:room]))
                        except Exception:  # noqa: BLE001 - a watcher's failure never stops the drain
                            self.on_log = None
        finally:
            os.close(self.fd)

    def text(self) -> str:
        text = self.kept.decode("utf-8", errors="replace")
        if self.total > len(self.kept):
            text += f"\n[log truncated: {self.total} bytes written, first {len(self.kept)} kept]"
        return text


@dataclass(frozen=True)
class _Hardening:
    """What a run adds to the jail (issue 24). Always all of it, except for the baseline of
    bench/bench_sandbox_hardening.py, which passes :data:`_BASELINE` to :func:`_run_sandboxed`
    directly: no option, config or argument of swarmdeck reaches this."""

    seccomp: bool = True
    keyring: bool = True
    cgroup: bool = True
    tmpfs: bool = True
    run_uid: bool = True


_FULL = _Hardening()
_BASELINE = _Hardening(seccomp=False, keyring=False, cgroup=False, tmpfs=False, run_uid=False)


@dataclass(frozen=True)
class _Setup:
    """One run's confinement, made by the trusted side before the child starts."""

    hardening: _Hardening
    uid: int | None
    group: cgroups.RunCgroup | None
    scratch_tmpfs: str | None  # tmpfs options of the scratch, None: a host folder bound read-write
    scratch_bytes: int


def _prepare_exec(setup: _Setup, scratch: Path) -> Callable[[], None] | None:
    """What bubblewrap's process does before it starts (as root): join the run's cgroup, a fresh
    session keyring, and a private mount namespace with the scratch tmpfs (bwrap binds it)."""
    procs = setup.group.procs_files if setup.group is not None else []
    keyring, tmpfs = setup.hardening.keyring, setup.scratch_tmpfs if os.geteuid() == 0 else None
    if not (procs or keyring or tmpfs):
        return None
    target = str(scratch.resolve())
    warm_keyctl()  # load libc through ctypes here: the forked child must not dlopen (another thread may hold its lock)
    warm_mounts()

    def prepare() -> None:  # runs in the forked child before exec: system calls only
        cgroups.join(procs)
        if keyring:
            join_session_keyring()
        if tmpfs is not None:
            private_mounts()
            mount_scratch(target, tmpfs)

    return prepare


class _Started:
    """A child started as a new program (bubblewrap, or unconfined): a Popen."""

    def __init__(self, argv: list[str], in_fd: int, out_fd: int, log_fd: int, scratch: Path, *,
                 prepare: Callable[[], None] | None = None, extra_fds: tuple[int, ...] = ()) -> None:
        env = dict(CHILD_ENV, HOME=str(scratch), TMPDIR=str(scratch))
        try:
            self.proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=log_fd, stderr=log_fd,
                                         pass_fds=(in_fd, out_fd, *extra_fds), env=env, cwd=str(scratch),
                                         start_new_session=True, preexec_fn=prepare)
        except subprocess.SubprocessError as exc:
            raise ConfinementUnavailable(f"the jail could not be prepared (the run's cgroup, session keyring "
                                         f"or scratch tmpfs): {exc}") from exc
        self.error: str | None = None
        self.cpu_s: float | None = None

    def wait(self, timeout: float) -> int | None:
        try:
            return self.proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            return None

    def kill(self) -> None:
        try:
            os.killpg(self.proc.pid, signal.SIGKILL)  # the whole session: bwrap and all it started
        except (ProcessLookupError, PermissionError):
            pass
        try:
            self.proc.kill()
        except ProcessLookupError:
            pass
        self.proc.wait()


class _Forked:
    """A child forked by the fork server into a fresh ``unshare`` jail; process A reports how it ended."""

    def __init__(self, root: Path, binds: list, symlinks: list, fds: tuple[int, int, int], **spawn: Any) -> None:
        self.status_fd, status_w = os.pipe()
        try:
            self.pid = shared_fork_server().spawn(root, binds, symlinks, (*fds, status_w), **spawn)
        except BaseException:
            os.close(self.status_fd)
            raise
        finally:
            os.close(status_w)
        self.status: dict[str, Any] | None = None
        self._data = b""

    def _read_status(self, timeout: float) -> bool:
        """Read A's report until the pipe closes (A ended) or ``timeout``; True once it closed."""
        deadline = time.monotonic() + timeout
        while self.status is None:
            left = deadline - time.monotonic()
            ready, _, _ = select.select([self.status_fd], [], [], max(0.0, left))
            if not ready:
                return False
            chunk = os.read(self.status_fd, 1 << 12)
            if chunk:
                self._data += chunk
                continue
            try:
                status = msgspec.msgpack.decode(self._data) if self._data else {}
            except msgspec.DecodeError:
                status = {}
            self.status = status if isinstance(status, dict) else {}
        return True

    @property
    def error(self) -> str | None:
        return None if self.status is None else self.status.get("error")

    @property
    def cpu_s(self) -> float | None:
        cpu = None if self.status is None else self.status.get("cpu_s")
        return float(cpu) if isinstance(cpu, (int, float)) else None

    def wait(self, timeout: float) -> int | None:
        if not self._read_status(timeout):
            return None
        code = self.status.get("code") if self.status else None
        return code if isinstance(code, int) else -signal.SIGKILL

    def kill(self) -> None:
        if self.status is None and not self._read_status(0.0):
            try:
                os.killpg(self.pid, signal.SIGKILL)  # A, the jail's init and the script: the namespace dies with its init
            except (ProcessLookupError, PermissionError):
                pass
            self._read_status(10.0)
        os.close(self.status_fd)


class _Child:
    """The jailed process and the trusted side's ends of its pipes."""

    def __init__(self, jail: str | None, jail_config: JailConfig, folder: Path, scratch: Path,
                 root: Path | None, setup: _Setup, env_dirs: tuple[Path, ...] = ()) -> None:
        to_child_r, self.to_child = os.pipe()
        self.from_child, from_child_w = os.pipe()
        self.log, log_w = os.pipe()
        closing = [to_child_r, from_child_w, log_w]
        try:
            tmpfs = setup.scratch_tmpfs
            if jail == "unshare":
                binds, symlinks = jail_layout(folder, scratch if tmpfs is None else None, env_dirs)
                self.process: _Started | _Forked = _Forked(
                    root, binds, symlinks, (to_child_r, from_child_w, log_w),
                    scratch=None if tmpfs is None else (scratch.resolve(), tmpfs),
                    cgroup=setup.group.procs_files if setup.group is not None else [], keyring=setup.hardening.keyring)
            else:
                # normalised, not resolved: a venv's python must stay the venv's; "…/bench/../.venv/bin/python" names a
                # folder the jail does not have
                argv = [os.path.abspath(sys.executable), "-s", "-m", "swarmdeck.console.sandbox.child", str(to_child_r),
                        str(from_child_w)]
                extra: tuple[int, ...] = ()
                if jail == "bwrap":
                    seccomp_fd = None
                    if setup.hardening.seccomp:
                        seccomp_fd, seccomp_w = os.pipe()
                        closing.append(seccomp_fd)
                        try:
                            os.write(seccomp_w, seccomp_filter.filter_program())  # < 1 KiB: fits the pipe
                        finally:
                            os.close(seccomp_w)
                        extra = (seccomp_fd,)
                    own_tmpfs = tmpfs is not None and os.geteuid() != 0  # no root: bwrap's tmpfs, size only
                    argv = bwrap_command(argv, folder, scratch, jail_config.bwrap, seccomp_fd=seccomp_fd,
                                         scratch_size=setup.scratch_bytes if own_tmpfs else None, extra=env_dirs)
                self.process = _Started(argv, to_child_r, from_child_w, log_w, scratch,
                                        prepare=_prepare_exec(setup, scratch), extra_fds=extra)
        except BaseException:
            for fd in (self.to_child, self.from_child, self.log):
                os.close(fd)
            raise
        finally:
            for fd in closing:
                os.close(fd)
        self.reader = FrameReader(self.from_child)
        self.poll = select.poll()
        self.poll.register(self.from_child, select.POLLIN)
        self.eof = False

    def send(self, frame: bytes | dict[str, Any]) -> bool:
        try:
            write_frame(self.to_child, frame)
            return True
        except (BrokenPipeError, OSError):
            return False

    def send_closed(self) -> None:
        """Close our writing end: a child blocked reading sees the end of the file."""
        if self.to_child >= 0:
            try:
                os.close(self.to_child)
            except OSError:
                pass
        self.to_child = -1

    def receive(self, deadline: float) -> tuple[bytes, bytes] | None:
        """(kind, body) of the next frame, or None at the deadline; EOFError when the child closed its end."""
        while True:
            frame = self.reader.next()
            if frame is not None:
                return frame
            if self.eof:
                raise EOFError
            timeout = deadline - time.monotonic()
            if timeout <= 0:
                return None
            if self.poll.poll(timeout * 1000.0) and not self.reader.feed():
                self.eof = True

    def kill(self, uid: int | None, grace: float = 0.0) -> None:
        """End the child: after ``grace`` s to exit by itself (a clean end), SIGKILL to all of it."""
        self.send_closed()
        if grace > 0:
            self.process.wait(grace)
        self.process.kill()
        if uid is not None and not (isinstance(self.process, _Forked) and self.process.status):
            kill_all_of(uid)  # (an unshare jail that reported its end is empty: the kernel ends a pid
            # namespace's init only after every other process in it is gone)
        try:
            os.close(self.from_child)
        except OSError:
            pass


def _exit_reason(process: _Started | _Forked) -> str:
    code = process.wait(5.0)
    if process.error:
        return process.error
    if code is None:
        return "the script's process stopped answering"
    if code < 0:
        name = signal.Signals(-code).name
    elif code > 128 and code - 128 in signal.Signals._value2member_map_:
        name = signal.Signals(code - 128).name  # the jail's init reports its child's signal as 128 + n
    else:
        return f"the script's process ended unexpectedly (exit status {code})"
    hint = {"SIGXCPU": " (CPU time limit)", "SIGKILL": " (killed: a resource limit)",
            "SIGXFSZ": " (file size limit)", "SIGSEGV": " (crashed)"}.get(name, "")
    return f"the script's process was killed by {name}{hint}"


def _note_cpu(outcome: SandboxOutcome, message: dict[str, Any]) -> None:
    cpu = message.get("cpu_s")
    if isinstance(cpu, float) and np.isfinite(cpu) and cpu >= 0:
        outcome.child_cpu_s = cpu
    if message.get("metrics"):
        _note_metrics(outcome, message["metrics"])


def _note_metrics(outcome: SandboxOutcome, values: Any) -> None:
    """The script's metrics (``metrics`` message, or with ``done``), checked; ProtocolError naming what is wrong."""
    try:
        outcome.metrics = check_metrics(values)
    except ValueError as exc:
        raise ProtocolError(f"'metrics': {exc}") from None


def _write_private(bundle: ScriptBundle, folder: Path, uid: int | None) -> Path:
    """The script's files for the jail, readable by the run alone: owned by us, group the run's gid (= its uid),
    folders 0750 and files 0640 — other local users read nothing of a researcher's script while it runs. Without
    a uid of the run's own the child runs as we do: 0700/0600."""
    if uid is None:
        return bundle.write_to(folder, file_mode=0o600, dir_mode=0o700)
    os.chmod(folder, 0o750)
    os.chown(folder, -1, uid)
    script = bundle.write_to(folder, file_mode=0o640, dir_mode=0o750)
    for path in folder.rglob("*"):
        os.chown(path, -1, uid, follow_symlinks=False)
    return script


def _use_sensors(plant: Plant, config: Any) -> None:
    """The script's sensors on the plant (a ``sensors`` message); ProtocolError when the plant has none to give."""
    use = getattr(plant, "use_sensors", None)
    try:
        if not callable(use):
            raise ValueError("this arena simulates no sensors for scripts")
        use(config)
    except ValueError as exc:
        raise ProtocolError(f"'sensors' message refused: {exc}") from None


def _make_plant(make_plant: PlantFactory, n: int, initial: NDArray[np.float64] | None,
                obstacles: NDArray[np.float64] | None) -> Plant:
    """``make_plant(n, initial)``, then the obstacles the script declared (``(M, 2, 2)`` m) made solid: passed as
    ``make_plant(..., obstacles=)`` to a factory that takes them (the portal builds its loop with them), else given
    to the plant's ``add_obstacles`` (an Arena's: barrier, contact, validation, sensors). ValueError (the Arena is
    refused) when they are invalid, or when the plant cannot hold them."""
    if obstacles is None:
        return make_plant(n, initial)
    try:
        takes = "obstacles" in inspect.signature(make_plant).parameters
    except (TypeError, ValueError):
        takes = False
    if takes:
        return make_plant(n, initial, obstacles=obstacles)  # type: ignore[call-arg]
    plant = make_plant(n, initial)
    add = getattr(plant, "add_obstacles", None)
    if add is None:
        raise ValueError("the script declares obstacles, and this arena cannot make them solid")
    add(obstacles)
    return plant


def run_sandboxed(
    script: str | Path | ScriptBundle,
    make_plant: PlantFactory,
    *,
    source: bytes | None = None,
    entry: str | None = None,
    n_robots: int | None = None,
    duration: float | None = None,
    rps: bool | None = None,
    limits: SandboxLimits = SandboxLimits(),
    trusted: bool = False,
    cancelled: Callable[[], bool] | None = None,
    jail: JailConfig = JailConfig(),
    argv: tuple[str, ...] | list[str] = (),
    rps_semantics: bool = False,
    rps_call_order: bool = True,
    on_log: Callable[[bytes], None] | None = None,
    bounds: tuple[float, float, float, float] | None = None,
    robot_model: str | None = DEFAULT_ROBOT_MODEL,
    rps_generation: int | None = None,
    params: Mapping[str, Any] | None = None,
) -> SandboxOutcome:
    """Run ``script`` in a jailed child against the plant ``make_plant(n, initial_poses)`` builds.

    ``script``: a ``.py`` file; a directory with its ``entry`` file (default ``main.py``);
    or a :class:`~swarmdeck.console.sandbox.bundle.ScriptBundle`. ``source``: the bytes of a
    single-file script (then ``script`` only names it). The child sees a copy of the files
    alone in a fresh folder of its own, read-only, with that folder first on ``sys.path``
    (sibling modules import); nothing else of this machine's files but what Python needs.
    ValueError when the script cannot be read or the bundle is invalid.

    ``n_robots``/``duration``: what an Arena built without arguments gets (declared values).
    ``jail``: which jails to try, in order (default: ``unshare``, then bubblewrap).
    ``trusted``: run without a jail when none works here (resource limits still apply);
    otherwise :class:`ConfinementUnavailable` is raised.
    ``jail.script_env``: the lab's script environment, bound read-only and put in force before the
    script's first line (:mod:`swarmdeck.console.sandbox.script_env`); :class:`ConfinementUnavailable`
    (naming what is wrong) when it breaks its rule.
    ``argv``: the script's arguments (its ``sys.argv[1:]``; it runs as ``__main__``);
    ``rps_semantics``/``rps_call_order``: the rps facade's modes in the child (``swarmdeck run --rps-semantics``,
    ``--no-rps-call-order``); ``robot_model``/``rps_generation``: the robot model the child's Arena and rps facade
    assume (:mod:`swarmdeck.core.robot_models`; default the GRITSBot, the robots of the lab's arena and of
    verification; None: the facade's choice by the script's rps generation) — give the plant's, so the script's
    constants match the robots ``make_plant`` drives. ``on_log(bytes)``: each piece of the script's output
    (stdout and stderr, within ``limits.log_bytes``) as it comes, on a reader thread.
    ``bounds``: the arena ``(x_min, x_max, y_min, y_max)`` (m) the script's Arena sees when it builds one without a
    config — its region of a shared floor (:mod:`swarmdeck.devices.fleet.regions`); None: the default floor.
    ``params``: the values ``swarmdeck.devices.params()`` returns in the script (JSON-able; a sweep's point);
    the script's recorded metrics come back in ``SandboxOutcome.metrics``.
    """
    if isinstance(script, ScriptBundle):
        bundle = script
    elif source is not None:
        bundle = ScriptBundle.single(Path(script).name, source)
    else:
        try:
            bundle = ScriptBundle.from_path(script, entry)
        except OSError as exc:
            raise ValueError(f"cannot read the script {str(script)!r}: {exc}") from exc
    script_options: dict[str, Any] = {"argv": [str(a) for a in argv], "rps_semantics": bool(rps_semantics),
                                      "rps_call_order": bool(rps_call_order), "robot_model": robot_model,
                                      "rps_generation": rps_generation}
    if bounds is not None:
        script_options["bounds"] = [float(v) for v in bounds]
    if params is not None:
        script_options["params"] = dict(params)
    return _run_sandboxed(bundle, make_plant, n_robots=n_robots, duration=duration, rps=rps, limits=limits,
                          trusted=trusted, cancelled=cancelled, jail=jail, hardening=_FULL, script_options=script_options,
                          on_log=on_log)


def _run_sandboxed(bundle: ScriptBundle, make_plant: PlantFactory, *, n_robots: int | None, duration: float | None,
                   rps: bool | None, limits: SandboxLimits, trusted: bool, cancelled: Callable[[], bool] | None,
                   jail: JailConfig, hardening: _Hardening,
                   script_options: dict[str, Any] | None = None,
                   on_log: Callable[[bytes], None] | None = None) -> SandboxOutcome:
    """:func:`run_sandboxed` with ``hardening`` (always :data:`_FULL` there)."""
    try:  # checked on every run: the lab may change the environment while a server runs
        env = None if jail.script_env is None else ScriptEnv.open(jail.script_env)
    except ValueError as exc:  # the machine's set-up, not the script: an infrastructure error
        raise ConfinementUnavailable(f"cannot run scripts with the lab's script environment: {exc}") from None
    chosen, reason = choose_jail(jail)
    if chosen is None and not trusted:
        raise ConfinementUnavailable(f"cannot confine untrusted code on this machine: {reason}; "
                                     "pass --trusted to run it unconfined")
    if chosen is not None and hardening.seccomp and (problem := seccomp_filter.probe()) is not None:
        raise ConfinementUnavailable(f"cannot confine untrusted code on this machine: no seccomp filter: {problem}")
    unhardened: list[str] = []
    scratch = Path(tempfile.mkdtemp(prefix="swarmdeck-scratch-"))
    folder = Path(tempfile.mkdtemp(prefix="swarmdeck-script-"))
    root = Path(tempfile.mkdtemp(prefix="swarmdeck-root-")) if chosen == "unshare" else None
    uid: int | None = None
    group: cgroups.RunCgroup | None = None
    try:
        if chosen is not None and os.geteuid() == 0:  # unconfined, the child keeps our uid (and our files)
            if hardening.run_uid:
                try:
                    uid = uids.allocate()
                except uids.UidUnavailable as exc:
                    raise ConfinementUnavailable(f"cannot confine untrusted code on this machine: {exc}") from exc
            else:
                uid = 200000 + os.getpid() % 100000  # the bench's baseline: the jail before issue 24
            os.chown(scratch, uid, uid)
        script = _write_private(bundle, folder, uid)
        if hardening.cgroup:
            try:
                group = cgroups.create(cgroups.CgroupLimits(
                    memory=limits.memory, processes=limits.processes + 2, cpu_cores=limits.cpu_cores,
                    cpus=tuple(sorted(os.sched_getaffinity(0)))), name=None if uid is None else str(uid))
            except cgroups.CgroupUnavailable as exc:
                if chosen is not None and not (jail.allow_no_cgroup or trusted):
                    raise ConfinementUnavailable(
                        f"cannot confine untrusted code on this machine: {exc}; pass --allow-no-cgroup to run it "
                        "without a per-run limit of memory, processes and CPU") from exc
                unhardened.append(f"no cgroup (only per-process limits): {exc}")
            if group is not None and group.missing:
                unhardened.append(f"the run's cgroup has no {' or '.join(group.missing)} controller: "
                                  "its CPU time or cores are not limited as a whole")
        tmpfs = None
        if chosen is not None and hardening.tmpfs:
            tmpfs = scratch_options(limits.scratch_bytes, limits.scratch_inodes, uid)
            if chosen == "bwrap" and os.geteuid() != 0:
                unhardened.append("scratch has no inode limit (bubblewrap's --size without root)")
        setup = _Setup(hardening, uid, group, tmpfs, limits.scratch_bytes)
        try:
            child = _Child(chosen, jail, folder, scratch, root, setup, () if env is None else (env.root,))
        except ForkServerError as exc:
            raise ConfinementUnavailable(str(exc)) from exc
        cpu_clock = None
        if group is not None and limits.tick_clock == "cpu" and group.cpu_time_s() is not None:
            cpu_clock = group.cpu_time_s
        with cgroups.OomGuard(group) if group is not None else contextlib.nullcontext():
            outcome = _loop(child, script, scratch, uid, make_plant, n_robots=n_robots, duration=duration, rps=rps,
                            limits=limits, cancelled=cancelled, jail=chosen, cpu_clock=cpu_clock,
                            seccomp=chosen == "unshare" and hardening.seccomp, script_options=script_options or {},
                            script_env=None if env is None else env.policy(), on_log=on_log)
        outcome.uid, outcome.unhardened = uid, unhardened
        outcome.cgroup = None if group is None else f"v{group.version}"
        if group is not None and group.oom_kills():
            line = (f"the run exceeded its memory limit of {limits.memory / (1 << 20):g} MiB (all its processes "
                    "together): the kernel killed it")
            outcome.ended_by, outcome.error_line, outcome.error = "memory", line, line
        return outcome
    finally:
        emptied = False
        if group is not None:
            problem = group.remove()
            emptied = problem is None  # a removed group held no task: nothing of the run is left
            if problem is not None:
                logging.getLogger(__name__).warning("the run's cgroup was not removed cleanly: %s", problem)
        if uid is not None and hardening.run_uid and (problem := uids.release(uid, processes_gone=emptied)):
            logging.getLogger(__name__).warning("uid %d is retired: %s", uid, problem)
        shutil.rmtree(scratch, ignore_errors=True)
        shutil.rmtree(folder, ignore_errors=True)
        if root is not None:
            shutil.rmtree(root, ignore_errors=True)


def _loop(child: _Child, script: Path, scratch: Path, uid: int | None, make_plant: PlantFactory, *,
          n_robots: int | None, duration: float | None, rps: bool | None, limits: SandboxLimits,
          cancelled: Callable[[], bool] | None, jail: str | None, seccomp: bool = False,
          script_env: dict[str, Any] | None = None, script_options: dict[str, Any] | None = None,
          cpu_clock: Callable[[], float | None] | None = None,
          on_log: Callable[[bytes], None] | None = None) -> SandboxOutcome:
    """The run: the child's start-up, then one exchange per tick until it ends (see the module docstring).

    ``cpu_clock``: the run's CPU time so far (s, its cgroup's count): each tick is then charged the CPU time
    its processes used since the poses were sent (``limits.tick_s``), within a wall backstop
    (``limits.tick_backstop_s``); None: wall time (``limits.tick_s``)."""
    outcome = SandboxOutcome(jail=jail)
    drain = _LogDrain(child.log, limits.log_bytes, on_log)
    drain.start()
    started = time.monotonic()
    wall_deadline = started + limits.wall_s

    def end(ended_by: str, line: str | None, full: str | None = None) -> None:
        outcome.ended_by, outcome.error_line, outcome.error = ended_by, line, full if full is not None else line

    try:
        child.send({"t": "start", "script": str(script), "n_robots": n_robots, "duration": duration, "rps": rps,
                    "rlimits": limits.rlimits(), "uid": uid, "scratch": str(scratch), "seccomp": seccomp,
                    "script_env": script_env, **(script_options or {})})
        plant: Plant | None = None
        ready: float | None = None  # when the child reported it is loaded and confined
        outstanding = False  # poses sent, commands not yet received
        sent = -1  # the tick number of the poses last sent
        consecutive = 0
        metrics_tick = -1  # the tick of the last 'metrics' message (one per tick at most)
        charged_from = (0.0, 0.0)  # (wall, CPU s) when the current tick's budget started
        waited_out = False  # a wait of the current tick ran out (only then is its CPU time read again)
        cores = os.cpu_count() or 1  # the run's processes use at most this many cores at once

        def cpu_now() -> float:
            value = cpu_clock() if cpu_clock is not None else None
            return charged_from[1] if value is None else value  # an unreadable count charges nothing more

        def start_budget() -> None:
            nonlocal charged_from, waited_out
            charged_from = (time.monotonic(), cpu_now() if cpu_clock is not None else 0.0)
            waited_out = False

        def tick_over(now: float) -> bool:
            """The current tick has used up its budget (CPU time, or wall time without a CPU clock) or its
            wall backstop."""
            if cpu_clock is None:
                return now >= charged_from[0] + limits.tick_s
            return (now >= charged_from[0] + limits.tick_backstop_s
                    or cpu_now() - charged_from[1] >= limits.tick_s)

        def missed() -> bool:
            """The script's answer for this tick is missing, late or stale: the robots stop for it and
            simulated time advances (True: that was one too many in a row, the run is over)."""
            nonlocal consecutive
            outcome.overruns += 1
            consecutive += 1
            plant.apply(None)
            outcome.ticks += 1
            start_budget()  # the next tick (a late answer to these poses is dropped when it comes)
            if consecutive >= limits.max_overruns:
                budget = (f"{limits.tick_s:g} s of CPU time (at most {limits.tick_backstop_s:g} s of wall time)"
                          if cpu_clock is not None else f"{limits.tick_s:g} s")
                end("overruns", f"the script missed its per-tick compute budget of {budget} in "
                                f"{consecutive} ticks in a row (no answer in time, or an answer for another tick; "
                                f"at t = {plant.observe()[0]:.2f} s)")
                return True
            return False

        while True:  # the deadline and a cancel are checked after every plant step
            if cancelled is not None and cancelled():
                end("cancelled", "the run was cancelled")
                break
            now = time.monotonic()
            if now >= wall_deadline:
                reached = "" if plant is None else f" (at t = {plant.observe()[0]:.2f} s simulated, {outcome.ticks} ticks)"
                end("wall", f"the run used up its wall-time limit of {limits.wall_s:g} s{reached}")
                break
            if ready is None:
                deadline = min(started + limits.boot_s, wall_deadline)
            elif plant is None:
                deadline = min(ready + limits.startup_s, wall_deadline)
            elif cpu_clock is None:
                deadline = min(charged_from[0] + limits.tick_s, wall_deadline)
            elif not waited_out:  # before tick_s / cores of wall time the run cannot have used its budget:
                # no clock read (one per tick, at its start: bench/RESULTS.md "sandbox per tick")
                deadline = min(charged_from[0] + limits.tick_s / cores, charged_from[0] + limits.tick_backstop_s,
                               wall_deadline)
            else:  # wake when the budget could be used up at one core, at the backstop at the latest
                left = limits.tick_s - (cpu_now() - charged_from[1])
                deadline = min(now + max(left, 0.0), charged_from[0] + limits.tick_backstop_s, wall_deadline)
            try:
                frame = child.receive(deadline)
            except EOFError:
                end("crash", _exit_reason(child.process))
                break
            except ProtocolError as exc:
                end("protocol", f"the script's process broke the protocol: {exc}")
                break
            if frame is None:
                if time.monotonic() >= wall_deadline:
                    continue  # reported at the top of the loop
                if ready is None:
                    end("boot", f"the sandbox did not start within {limits.boot_s:g} s")
                    break
                if plant is None:
                    end("startup", f"the script did not build its Arena within {limits.startup_s:g} s "
                                   "(an endless loop at import time?)")
                    break
                waited_out = True
                if not tick_over(time.monotonic()):
                    continue  # waiting without using CPU (sleeping, or not scheduled on a loaded machine)
                if missed():
                    break
                if plant.finished():
                    end("duration", None)
                    break
                continue
            kind, body = frame
            try:
                if kind == COMMANDS:
                    if plant is None or not outstanding:
                        raise ProtocolError("commands sent before the poses they answer")
                    k, nominal = commands(body, plant.n)
                    outstanding = False
                    if k != sent:  # an answer for other poses than those sent: a missed tick
                        if missed():
                            break
                    elif k != outcome.ticks:
                        pass  # the late answer to poses whose tick was already counted missed: dropped
                    else:
                        plant.apply(nominal)
                        outcome.ticks += 1
                        consecutive = 0
                elif kind != MESSAGE:
                    raise ProtocolError(f"unexpected {kind!r} frame")
                else:
                    message = decode(body)
                    t = message["t"]
                    if t == "done":
                        _note_cpu(outcome, message)
                        error, line = message.get("error"), message.get("error_line")
                        if error is not None or line is not None:
                            end("error", str(line or error)[:2000], str(error or line)[:20000])
                        else:
                            end("script", None)
                        break
                    if t == "ready" and ready is None:
                        ready = time.monotonic()
                        continue
                    if t == "network" and plant is not None and outstanding:  # display only (protocol.py)
                        traffic = network_traffic(message, plant.n)  # checked whatever the plant does with it
                        show = getattr(plant, "show_network", None)  # SandboxPlant: the loop's Frames show it
                        if callable(show):
                            show(*traffic)
                        continue
                    if t == "metrics" and plant is not None and outstanding:  # before tick k's commands
                        if message.get("k") != sent or metrics_tick == sent:
                            raise ProtocolError("'metrics' at most once per tick, before its commands")
                        metrics_tick = sent
                        _note_metrics(outcome, message.get("values"))
                        continue
                    if t == "decentralised" and plant is not None:  # the network lives here (network_link.py)
                        use_network = getattr(plant, "use_network", None)
                        if not callable(use_network):
                            raise ProtocolError("this arena models no network for decentralised scripts")
                        use_network(network_config_from_message(message))
                        child.send(plant.inboxes(sent))  # type: ignore[attr-defined]
                        continue
                    if t == "outbox" and plant is not None and outstanding:
                        plant.post_messages(message)  # type: ignore[attr-defined]
                        continue
                    if t == "sensors" and plant is not None:  # computed here, sent with every tick (senses.py)
                        config = message.get("config")
                        _use_sensors(plant, None if config is None else sensing_from_message(message))
                        continue
                    if t == "leds" and plant is not None:
                        set_leds = getattr(plant, "set_leds", None)
                        if callable(set_leds):
                            set_leds(leds_from_message(message, plant.n))
                        continue
                    if t == "draw" and plant is not None:
                        draw = getattr(plant, "draw", None)
                        if draw is not None:
                            draw(decode_draw(message))
                        continue
                    if t != "arena" or plant is not None or ready is None:
                        raise ProtocolError(f"unexpected {t!r} message")
                    n = message.get("n")
                    if not isinstance(n, int) or n < 1:
                        raise ProtocolError(f"'arena' message: n must be a positive integer, got {n!r}")
                    ic = None if message.get("initial") is None else floats(message, "initial", (n, 3))
                    declared = script_obstacles(message)
                    outcome.n_robots = n
                    try:
                        plant = _make_plant(make_plant, n, ic, declared)
                    except ValueError as exc:
                        child.send({"t": "end", "reason": str(exc)})
                        end("arena", f"the Arena the script asked for was refused: {exc}")
                        break
                    outcome.plant = plant
            except ProtocolError as exc:
                end("protocol", f"the script's process broke the protocol: {exc}")
                break
            if plant.finished():
                child.send({"t": "end", "reason": "declared duration is over"})
                try:
                    last = child.receive(min(time.monotonic() + limits.tick_s, wall_deadline))
                    if last is not None and last[0] == MESSAGE:
                        message = decode(last[1])
                        if message.get("t") == "done":
                            _note_cpu(outcome, message)
                except (EOFError, ProtocolError):  # (bad metrics with 'done': the run's own ones are kept)
                    pass
                end("duration", None)
                break
            if not outstanding:
                t_now, poses = plant.observe()
                sent = outcome.ticks
                start_budget()
                readings = getattr(plant, "readings", None)
                sensed = readings() if callable(readings) else None
                if sensed is not None:  # what the robots sensed, before the poses of the same tick
                    child.send(readings_message(sent, sensed))
                inboxes = getattr(plant, "inboxes", None)
                delivered = inboxes(sent) if callable(inboxes) else None
                if delivered is not None:  # the trusted network's deliveries of this tick
                    child.send(delivered)
                child.send(encode_poses(sent, t_now, poses))
                outstanding = True
    finally:
        clean = outcome.ended_by in ("script", "duration", "error")  # the child exits by itself (its CPU time is counted)
        child.kill(uid, grace=2.0 if clean else 0.0)
        if child.process.cpu_s is not None:
            outcome.child_cpu_s = child.process.cpu_s  # measured outside the jail: every process in it
        drain.join(timeout=5)
        outcome.log, outcome.log_bytes = drain.text(), drain.total
    return outcome
