"""Kernel keyrings and per-run uids, in both jails: a script sees no inherited keyring, leaves no key
for the next run, and every run has a uid of its own (asserted from the trusted side)."""
import json
import os
import subprocess
import sys
import textwrap

import pytest

from swarmdeck.console.sandbox import keyrings, uids
from swarmdeck.console.sandbox.confinement import JAILS, processes_of

needs_root = pytest.mark.skipif(os.geteuid() != 0, reason="per-run uids and keyring clearing need root")

READER = """
import ctypes, errno
libc = ctypes.CDLL(None, use_errno=True)
libc.syscall.restype = ctypes.c_long
buf = ctypes.create_string_buffer(4096)
def report(name, result):
    code = ctypes.get_errno() if result < 0 else 0
    print("CALL", name, errno.errorcode.get(code, "OK"), flush=True)
report("read_session", libc.syscall(250, 11, -3, buf, 4096))       # KEYCTL_READ @s: the keys it holds
report("search_session", libc.syscall(250, 10, -3, b"user", b"swarmdeck-test-secret", 0))
report("add_session", libc.syscall(248, b"user", b"planted-by-script", b"x", 1, -3))
report("add_user", libc.syscall(248, b"user", b"left-for-next-run", b"x", 1, -4))
report("add_user_session", libc.syscall(248, b"user", b"left-for-next-run", b"x", 1, -5))
report("read_user", libc.syscall(250, 11, -4, buf, 4096))
try:
    print("PROCKEYS", open("/proc/keys").read().replace("\\n", " | "))
except OSError as exc:
    print("PROCKEYS unreadable", type(exc).__name__)
import os
print("UID", os.getuid())
def experiment(arena):
    arena.step()
"""

# Runs in a fresh interpreter: joins a keyring of its own (the test never touches the keyring of whoever
# started pytest), plants a secret there, and only then starts the jails (the fork server inherits it).
PLANTED = """
import json, sys
from pathlib import Path
from swarmdeck.console.sandbox import keyrings
from swarmdeck.console.sandbox.confinement import JailConfig
from swarmdeck.console.sandbox.plant import ArenaPlant
from swarmdeck.console.sandbox.run import run_sandboxed
from swarmdeck.devices.arena import Arena
import ctypes
keyrings.join_session_keyring()
libc = ctypes.CDLL(None, use_errno=True)
libc.syscall.restype = ctypes.c_long
secret = libc.syscall(248, b"user", b"swarmdeck-test-secret", b"TOPSECRET", 9, -3)
assert secret > 0
def before():
    buf = ctypes.create_string_buffer(4096)
    n = libc.syscall(250, 11, -3, buf, 4096)
    return sorted(int.from_bytes(buf.raw[i:i + 4], "little") for i in range(0, n, 4))
keys_before = before()
out = run_sandboxed(sys.argv[1], lambda n, ic: ArenaPlant(Arena(n, initial_conditions=ic, duration=0.2)), n_robots=2,
                    duration=0.2, jail=JailConfig(order=(sys.argv[2],)))
print(json.dumps({"ok": out.ok, "error": out.error, "log": out.log, "secret": secret, "keys_before": keys_before,
                  "keys_after": before(), "jail": out.jail}))
"""


def calls(log):
    return {line.split()[1]: line.split()[2] for line in log.splitlines() if line.startswith("CALL ")}


@pytest.mark.parametrize("jail", JAILS)
def test_an_inherited_session_keyring_can_be_neither_read_nor_added_to(tmp_path, jail):
    script = tmp_path / "reader.py"
    script.write_text(textwrap.dedent(READER))
    done = subprocess.run([sys.executable, "-c", PLANTED, str(script), jail], capture_output=True, text=True,
                          cwd=tmp_path, timeout=300, check=False)
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result["ok"] and result["jail"] == jail, result["error"]
    got = calls(result["log"])
    for name in ("read_session", "search_session", "add_session", "add_user", "add_user_session", "read_user"):
        assert got[name] == "EPERM", (name, result["log"])
    assert "TOPSECRET" not in result["log"] and "swarmdeck-test-secret" not in result["log"]
    # the trusted side's keyring holds exactly what it held before: nothing was planted
    assert result["keys_after"] == result["keys_before"] == [result["secret"]]


@needs_root
def test_each_run_has_a_uid_of_its_own_and_leaves_no_key_or_process(jail_run):
    first, second = jail_run(READER), jail_run(READER)
    assert first.ok and second.ok, (first.error, second.error)
    uid_lines = [[line for line in out.log.splitlines() if line.startswith("UID ")] for out in (first, second)]
    assert uid_lines == [[f"UID {first.uid}"], [f"UID {second.uid}"]]
    assert first.uid != second.uid and all(uids.UID_RANGE[0] <= u < uids.UID_RANGE[1] for u in (first.uid, second.uid))
    for out in (first, second):
        assert calls(out.log)["add_user"] == "EPERM" and calls(out.log)["read_user"] == "EPERM"
        assert out.uid not in keyrings.uids_with_keys() and processes_of(out.uid) == []
        assert not (uids.STATE_DIR / str(out.uid)).exists()  # reservation released after a clean end


def _as_uid(uid, action):
    """Run ``action()`` in a forked process that took ``uid``; its return value (an int)."""
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:  # pragma: no cover
        os.close(read)
        try:
            os.setgroups([])
            os.setresgid(uid, uid, uid)
            os.setresuid(uid, uid, uid)
            value = action()
        except BaseException:  # noqa: BLE001
            value = -1
        os.write(write, str(value).encode())
        os._exit(0)
    os.close(write)
    with os.fdopen(read) as f:
        value = int(f.read())
    os.waitpid(pid, 0)
    return value


@needs_root
def test_clearing_a_uids_keyrings_removes_what_a_previous_holder_left():
    import ctypes

    uid = uids.allocate()
    libc = ctypes.CDLL(None, use_errno=True)
    libc.syscall.restype = ctypes.c_long

    def plant():
        return libc.syscall(248, b"user", b"left-behind", b"SECRET", 6, keyrings.KEY_SPEC_USER_KEYRING)

    def count():
        buf = ctypes.create_string_buffer(4096)
        return libc.syscall(250, keyrings.KEYCTL_READ, keyrings.KEY_SPEC_USER_KEYRING, buf, 4096) // 4

    try:
        assert _as_uid(uid, plant) > 0
        assert uid in keyrings.uids_with_keys() and _as_uid(uid, count) == 1
        keyrings.clear_user_keyrings(uid)
        assert _as_uid(uid, count) == 0  # the next holder of the uid finds an empty keyring
    finally:
        assert uids.release(uid) is None
