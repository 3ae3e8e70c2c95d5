"""Scratch is a tmpfs of the run's own in both jails, limited in bytes and in files: filling it is ENOSPC for
the script, and nothing lands on the host's disk."""

from swarmdeck.console.sandbox.confinement import SandboxLimits

FILL_BYTES = """
import errno, os
written, code = 0, None
chunk = b"x" * (1 << 20)
try:
    for i in range(200):              # 200 MiB in files of 8 MiB (each below RLIMIT_FSIZE)
        with open(f"big{i}", "wb") as f:
            for _ in range(8):
                f.write(chunk)
                f.flush()
                written += len(chunk)
        if written >= 200 << 20:
            break
except OSError as exc:
    code = errno.errorcode.get(exc.errno)
print("WROTE", written, code)
st = os.statvfs(".")
print("FS", st.f_blocks * st.f_frsize, st.f_files)
def experiment(arena):
    arena.step()
"""

FILL_FILES = """
import errno, os
made, code = 0, None
try:
    for i in range(20000):
        open(f"f{i}", "w").close()
        made += 1
except OSError as exc:
    code = errno.errorcode.get(exc.errno)
print("MADE", made, code)
def experiment(arena):
    arena.step()
"""


def line(log, tag):
    return next(x.split()[1:] for x in log.splitlines() if x.startswith(tag + " "))


def test_200_mib_in_scratch_is_refused_at_the_limit(jail_run):
    out = jail_run(FILL_BYTES)
    assert out.ok, out.error
    written, code = line(out.log, "WROTE")
    assert code == "ENOSPC" and (64 - 8) << 20 <= int(written) <= 64 << 20
    assert line(out.log, "FS") == [str(64 << 20), "4096"]


def test_20000_files_in_scratch_are_refused_at_the_inode_limit(jail_run):
    out = jail_run(FILL_FILES)
    assert out.ok, out.error
    made, code = line(out.log, "MADE")
    assert code == "ENOSPC" and 4000 <= int(made) < 4096


def test_the_limits_are_configurable(jail_run):
    out = jail_run(FILL_FILES, SandboxLimits(scratch_bytes=4 << 20, scratch_inodes=100))
    assert out.ok, out.error
    made, code = line(out.log, "MADE")
    assert code == "ENOSPC" and 90 <= int(made) < 100
    out = jail_run(FILL_BYTES, SandboxLimits(scratch_bytes=16 << 20))
    written, code = line(out.log, "WROTE")
    assert code == "ENOSPC" and int(written) <= 16 << 20
    assert line(out.log, "FS") == [str(16 << 20), "4096"]  # a file system of its own, not the host's /tmp
