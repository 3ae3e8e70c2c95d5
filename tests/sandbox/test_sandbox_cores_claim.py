"""A worker without an index (a Ray worker) claims a core of its own on this machine: two claimants at once get
different cores, a core comes free when its holder ends, and with every core held a claimant stays unpinned
(console/sandbox/cores.py)."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

CLAIM = """
import os, sys
from pathlib import Path
from swarmdeck.console.sandbox.cores import claim_core
core = claim_core(Path(sys.argv[1]))
print(core, sorted(os.sched_getaffinity(0)), flush=True)
sys.stdin.read()  # hold the claim until the test closes our stdin
"""

CORES = sorted(os.sched_getaffinity(0))


def claimant(folder: Path) -> tuple[subprocess.Popen, str | None, list[int]]:
    proc = subprocess.Popen([sys.executable, "-c", CLAIM, str(folder)], stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, text=True)
    assert proc.stdout is not None
    line = proc.stdout.readline()  # ends: the child prints at once, or dies (then the line is empty)
    assert line, f"the claimant ended without answering (status {proc.wait(timeout=60)})"
    core, affinity = line.split(" ", 1)
    return proc, None if core == "None" else core, [int(c) for c in affinity.strip(" []\n").split(",")]


def release(proc: subprocess.Popen) -> None:
    assert proc.stdin is not None
    proc.stdin.close()
    assert proc.wait(timeout=60) == 0


@pytest.mark.skipif(len(CORES) < 2, reason="one core: nothing to share out")  # every machine CI runs on has 2+
def test_claimants_get_cores_of_their_own_until_none_is_left(tmp_path) -> None:
    held = [claimant(tmp_path) for _ in CORES]
    try:
        cores = [core for _, core, _ in held]
        assert None not in cores and len(set(cores)) == len(CORES), cores
        assert all(affinity == [int(core)] for _, core, affinity in held if core is not None)
        extra, none, affinity = claimant(tmp_path)
        assert none is None and affinity == CORES, "with every core held a claimant stays unpinned"
        release(extra)
        first = held.pop(0)
        release(first[0])
        again, core, affinity = claimant(tmp_path)
        held.append((again, core, affinity))
        assert core == first[1] and affinity == [int(core)], "the ended holder's core is free again"
    finally:
        for proc, _, _ in held:
            release(proc)
