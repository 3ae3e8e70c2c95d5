"""The trusted side of a sandboxed run: start the jailed child, exchange poses and commands per tick.

The user's script runs in :mod:`swarmdeck.console.jobs.child`, inside the jail
of :mod:`swarmdeck.console.jobs.confinement`. This module owns the loop: each
tick it sends the poses the script may see and waits — at most the per-tick
budget — for the script's commands, then hands them to the :class:`Plant`
(the simulator with the safety filter, later the real robots). A tick whose
commands do not arrive in time stops the robots for that tick;
``max_overruns`` such ticks in a row end the run. Whatever the child does (dies,
hangs, floods its output, sends garbage), the run ends with a
:class:`SandboxOutcome` naming the reason, and the child and everything it
started are killed.

API (for the portal and other callers)::

    from swarmdeck.console.jobs.bundle import ScriptBundle
    from swarmdeck.console.jobs.sandbox import run_sandboxed
    from swarmdeck.console.jobs.verification import VerificationConfig, verify

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
jail binds read-only; the script's working directory is a private scratch folder
(the only writable place, deleted afterwards). Bundle limits and the checks on
file names (relative paths only, no symlinks): :mod:`swarmdeck.console.jobs.bundle`;
invalid bundles raise ValueError naming the problem. Where this machine cannot
confine code, :class:`~swarmdeck.console.jobs.confinement.ConfinementUnavailable`
is raised unless ``trusted=True``.
"""
from __future__ import annotations

import os
import select
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from swarmdeck.console.jobs.bundle import ScriptBundle
from swarmdeck.console.jobs.confinement import (
    ConfinementUnavailable,
    SandboxLimits,
    bwrap_command,
    kill_all_of,
    probe,
    sandbox_uid,
)
from swarmdeck.console.jobs.protocol import FrameReader, ProtocolError, floats, pack, write_frame


class Plant(Protocol):
    """What the trusted loop drives: the simulator (or robots) behind the safety filter."""

    n: int

    def observe(self) -> tuple[float, NDArray[np.float64]]:
        """(time s, poses (N, 3)) the script may see now."""

    def apply(self, v: NDArray[np.float64] | None, w: NDArray[np.float64] | None) -> None:
        """One tick with the script's unicycle commands (N,) each; None: the script missed the tick (stop)."""

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
    ``"protocol"`` (the child sent something invalid), ``"arena"`` (the Arena it asked for was
    refused), ``"cancelled"``. ``error_line``: the reason in one line (None for clean ends).
    """

    ended_by: str = "script"
    error: str | None = None
    error_line: str | None = None
    n_robots: int | None = None
    ticks: int = 0
    overruns: int = 0
    child_cpu_s: float | None = None  # the child's CPU time as it reported it (informational, untrusted)
    script_invalid: int = 0  # robot-steps the script's own Arena stopped for NaN/inf commands (it says)
    log: str = ""
    log_bytes: int = 0
    plant: Any = field(default=None, repr=False)

    @property
    def ok(self) -> bool:
        return self.error_line is None


class _LogDrain(threading.Thread):
    """Reads the child's stdout+stderr to the end, keeping the first ``limit`` bytes."""

    def __init__(self, stream: Any, limit: int) -> None:
        super().__init__(daemon=True)
        self.stream, self.limit = stream, limit
        self.kept = bytearray()
        self.total = 0

    def run(self) -> None:
        while True:
            try:
                chunk = self.stream.read1(1 << 16)
            except (OSError, ValueError):
                return
            if not chunk:
                return
            self.total += len(chunk)
            room = self.limit - len(self.kept)
            if room > 0:
                self.kept += chunk[:room]

    def text(self) -> str:
        text = self.kept.decode("utf-8", errors="replace")
        if self.total > len(self.kept):
            text += f"\n[log truncated: {self.total} bytes written, first {len(self.kept)} kept]"
        return text


class _Child:
    """The jailed process and both ends of its pipes."""

    def __init__(self, script_dir: Path, scratch: Path, confined: bool) -> None:
        to_child_r, self.to_child = os.pipe()
        self.from_child, from_child_w = os.pipe()
        argv = [sys.executable, "-s", "-m", "swarmdeck.console.jobs.child", str(to_child_r), str(from_child_w)]
        if confined:
            argv = bwrap_command(argv, script_dir, scratch)
        env = {"PATH": "/usr/bin:/bin", "LANG": "C.UTF-8", "HOME": str(scratch), "TMPDIR": str(scratch),
               "PYTHONHASHSEED": "0", "PYTHONDONTWRITEBYTECODE": "1", "PYTHONUNBUFFERED": "1",
               "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
        try:
            self.proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                         stderr=subprocess.STDOUT, pass_fds=(to_child_r, from_child_w), env=env,
                                         cwd=str(scratch), start_new_session=True)
        finally:
            os.close(to_child_r)
            os.close(from_child_w)
        self.reader = FrameReader(self.from_child)
        self.eof = False

    def send(self, message: dict[str, Any]) -> bool:
        try:
            write_frame(self.to_child, message)
            return True
        except (BrokenPipeError, OSError):
            return False

    def send_closed(self) -> None:
        """Close our writing end: a child blocked reading sees the end of the file."""
        try:
            os.close(self.to_child)
        except OSError:
            pass
        self.to_child = -1

    def receive(self, deadline: float) -> dict[str, Any] | None:
        """The next message, or None at the deadline; EOFError when the child closed its end."""
        while True:
            message = self.reader.next()
            if message is not None:
                return message
            if self.eof:
                raise EOFError
            timeout = deadline - time.monotonic()
            if timeout <= 0:
                return None
            ready, _, _ = select.select([self.from_child], [], [], timeout)
            if ready and not self.reader.feed():
                self.eof = True

    def kill(self, uid: int | None, grace: float = 0.0) -> None:
        """End the child: after ``grace`` s to exit by itself (a clean end), SIGKILL to all of it."""
        self.send_closed()
        if grace > 0:
            try:
                self.proc.wait(timeout=grace)
            except subprocess.TimeoutExpired:
                pass
        try:
            os.killpg(self.proc.pid, signal.SIGKILL)  # the whole session: bwrap and all it started
        except (ProcessLookupError, PermissionError):
            pass
        try:
            self.proc.kill()
        except ProcessLookupError:
            pass
        self.proc.wait()
        if uid is not None:
            kill_all_of(uid)
        try:
            os.close(self.from_child)
        except OSError:
            pass


def _exit_reason(proc: subprocess.Popen) -> str:
    try:
        code = proc.wait(timeout=5)
    except subprocess.TimeoutExpired:
        return "the script's process stopped answering"
    if code < 0:
        name = signal.Signals(-code).name
    elif code > 128 and code - 128 in signal.Signals._value2member_map_:
        name = signal.Signals(code - 128).name  # bwrap reports its child's signal as 128 + n
    else:
        return f"the script's process ended unexpectedly (exit status {code})"
    hint = {"SIGXCPU": " (CPU time limit)", "SIGKILL": " (killed: a resource limit)",
            "SIGXFSZ": " (file size limit)", "SIGSEGV": " (crashed)"}.get(name, "")
    return f"the script's process was killed by {name}{hint}"


def _note_cpu(outcome: SandboxOutcome, message: dict[str, Any]) -> None:
    cpu = message.get("cpu_s")
    if isinstance(cpu, float) and np.isfinite(cpu) and cpu >= 0:
        outcome.child_cpu_s = cpu


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
) -> SandboxOutcome:
    """Run ``script`` in a jailed child against the plant ``make_plant(n, initial_poses)`` builds.

    ``script``: a ``.py`` file; a directory with its ``entry`` file (default ``main.py``);
    or a :class:`~swarmdeck.console.jobs.bundle.ScriptBundle`. ``source``: the bytes of a
    single-file script (then ``script`` only names it). The child sees a copy of the files
    alone in a fresh folder of its own, read-only, with that folder first on ``sys.path``
    (sibling modules import); nothing else of this machine's files but what Python needs.
    ValueError when the script cannot be read or the bundle is invalid.

    ``n_robots``/``duration``: what an Arena built without arguments gets (declared values).
    ``trusted``: run without the namespace jail when this machine cannot build one (resource
    limits still apply); otherwise :class:`ConfinementUnavailable` is raised.
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
    reason = probe()
    if reason is not None and not trusted:
        raise ConfinementUnavailable(f"cannot confine untrusted code on this machine: {reason}; "
                                     "pass --trusted to run it unconfined")
    scratch = Path(tempfile.mkdtemp(prefix="swarmdeck-scratch-"))
    folder = Path(tempfile.mkdtemp(prefix="swarmdeck-script-"))
    os.chmod(folder, 0o755)
    script = bundle.write_to(folder)
    uid = sandbox_uid() if reason is None else None  # unconfined, the child keeps our uid (and our files)
    if uid is not None:
        os.chown(scratch, uid, uid)
    outcome = SandboxOutcome()
    child = _Child(folder, scratch, confined=reason is None)
    drain = _LogDrain(child.proc.stdout, limits.log_bytes)
    drain.start()
    started = time.monotonic()
    wall_deadline = started + limits.wall_s

    def end(ended_by: str, line: str | None, full: str | None = None) -> None:
        outcome.ended_by, outcome.error_line, outcome.error = ended_by, line, full if full is not None else line

    try:
        child.send({"t": "start", "script": str(script), "n_robots": n_robots, "duration": duration, "rps": rps,
                    "rlimits": limits.rlimits(), "uid": uid, "scratch": str(scratch)})
        plant: Plant | None = None
        ready: float | None = None  # when the child reported it is loaded and confined
        outstanding = False  # poses sent, commands not yet received
        consecutive = 0
        while True:
            if cancelled is not None and cancelled():
                end("cancelled", "the run was cancelled")
                break
            now = time.monotonic()
            if now >= wall_deadline:
                end("wall", f"the script exceeded the wall-time limit of {limits.wall_s:g} s")
                break
            if ready is None:
                deadline = min(started + limits.boot_s, wall_deadline)
            elif plant is None:
                deadline = min(ready + limits.startup_s, wall_deadline)
            else:
                deadline = min(now + limits.tick_s, wall_deadline)
            try:
                message = child.receive(deadline)
            except EOFError:
                end("crash", _exit_reason(child.proc))
                break
            except ProtocolError as exc:
                end("protocol", f"the script's process broke the protocol: {exc}")
                break
            if message is None:
                if time.monotonic() >= wall_deadline:
                    continue  # reported at the top of the loop
                if ready is None:
                    end("boot", f"the sandbox did not start within {limits.boot_s:g} s")
                    break
                if plant is None:
                    end("startup", f"the script did not build its Arena within {limits.startup_s:g} s "
                                   "(an endless loop at import time?)")
                    break
                outcome.overruns += 1
                consecutive += 1
                plant.apply(None, None)
                outcome.ticks += 1
                if consecutive >= limits.max_overruns:
                    end("overruns", f"the script overran its per-tick compute budget of {limits.tick_s:g} s "
                                    f"in {consecutive} ticks in a row (at t = {plant.observe()[0]:.2f} s)")
                    break
                if plant.finished():
                    end("duration", None)
                    break
                continue
            kind = message["t"]
            try:
                if kind == "done":
                    _note_cpu(outcome, message)
                    error, line = message.get("error"), message.get("error_line")
                    if error is not None or line is not None:
                        end("error", str(line or error)[:2000], str(error or line)[:20000])
                    else:
                        end("script", None)
                    break
                if kind == "ready" and ready is None:
                    ready = time.monotonic()
                    continue
                if kind == "arena" and plant is None and ready is not None:
                    n = message.get("n")
                    if not isinstance(n, int) or n < 1:
                        raise ProtocolError(f"'arena' message: n must be a positive integer, got {n!r}")
                    ic = None if message.get("initial") is None else floats(message, "initial", (n, 3))
                    outcome.n_robots = n
                    try:
                        plant = make_plant(n, ic)
                    except ValueError as exc:
                        child.send({"t": "end", "reason": str(exc)})
                        end("arena", f"the Arena the script asked for was refused: {exc}")
                        break
                    outcome.plant = plant
                elif kind == "cmd" and plant is not None and outstanding:
                    if message.get("k") != outcome.ticks:
                        outstanding = False  # commands for stale poses (after an overrun): dropped
                    else:
                        invalid = message.get("invalid", 0)
                        if isinstance(invalid, int) and invalid >= 0:
                            outcome.script_invalid = max(outcome.script_invalid, invalid)
                        v = floats(message, "v", (plant.n,))
                        w = floats(message, "w", (plant.n,))
                        plant.apply(v, w)
                        outcome.ticks += 1
                        consecutive = 0
                        outstanding = False
                else:
                    raise ProtocolError(f"unexpected {kind!r} message")
            except ProtocolError as exc:
                end("protocol", f"the script's process broke the protocol: {exc}")
                break
            if plant.finished():
                child.send({"t": "end", "reason": "declared duration is over"})
                try:
                    last = child.receive(min(time.monotonic() + limits.tick_s, wall_deadline))
                    if last is not None and last.get("t") == "done":
                        _note_cpu(outcome, last)
                except (EOFError, ProtocolError):
                    pass
                end("duration", None)
                break
            if not outstanding:
                t, poses = plant.observe()
                child.send({"t": "poses", "k": outcome.ticks, "time": t, "poses": pack(poses)})
                outstanding = True
    finally:
        clean = outcome.ended_by in ("script", "duration", "error")  # the child exits by itself (its CPU time is counted)
        child.kill(uid, grace=2.0 if clean else 0.0)
        drain.join(timeout=5)
        outcome.log, outcome.log_bytes = drain.text(), drain.total
        shutil.rmtree(scratch, ignore_errors=True)
        shutil.rmtree(folder, ignore_errors=True)
    return outcome
