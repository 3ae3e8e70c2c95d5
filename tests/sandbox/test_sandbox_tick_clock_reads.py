"""A tick answered at once costs the trusted side one read of the run's CPU clock (its cgroup's count, from a file
kept open): the clock is read again only once the tick's wait ran out (console/sandbox/run.py, cgroups.py)."""
from __future__ import annotations

import os

import pytest

from swarmdeck.console.sandbox import cgroups
from swarmdeck.console.sandbox.confinement import SandboxLimits, probe
from swarmdeck.console.sandbox.plant import ArenaPlant
from swarmdeck.console.sandbox.run import run_sandboxed
from swarmdeck.devices.arena import Arena

pytestmark = pytest.mark.skipif(probe() is not None or cgroups.probe() is not None,
                                reason=f"no confinement or cgroup here: {probe() or cgroups.probe()}")

STEPS = 40


def test_each_tick_reads_the_cpu_clock_once(tmp_path, monkeypatch) -> None:
    reads = []
    real = cgroups.RunCgroup.cpu_time_s

    def counted(group: cgroups.RunCgroup) -> float | None:
        value = real(group)
        reads.append(value)
        return value

    monkeypatch.setattr(cgroups.RunCgroup, "cpu_time_s", counted)
    script = tmp_path / "script.py"
    script.write_text(f"def experiment(arena):\n    for _ in range({STEPS}):\n        arena.step()\n")
    # a budget of 100 s of CPU: no wait of a tick runs out before 100 s / cores of wall time, even on a loaded machine
    out = run_sandboxed(script, lambda n, ic: ArenaPlant(Arena(n, initial_conditions=ic, duration=60.0)),
                        n_robots=2, duration=60.0, limits=SandboxLimits(tick_s=100.0))
    assert out.ok and out.ticks == STEPS and out.overruns == 0, out.error
    assert reads and all(r is not None and r >= 0 for r in reads)
    assert reads == sorted(reads), "the run's CPU time never goes back"
    # the probe before the run, one per tick sent (STEPS + the last, unanswered, poses)
    assert len(reads) <= STEPS + 3, f"{len(reads)} reads of the CPU clock for {STEPS} ticks"


def test_the_clock_file_is_opened_once_and_closed_with_the_group() -> None:
    group = cgroups.create(cgroups.CgroupLimits(memory=64 << 20, processes=8, cpu_cores=1.0,
                                                cpus=tuple(sorted(os.sched_getaffinity(0)))))
    before = set(os.listdir("/proc/self/fd"))
    try:
        first, second = group.cpu_time_s(), group.cpu_time_s()
        assert first is not None and second is not None and 0 <= first <= second
        assert len(set(os.listdir("/proc/self/fd")) - before) == 1, "one file kept open for the clock"
    finally:
        assert group.remove() is None
    assert set(os.listdir("/proc/self/fd")) <= before, "the clock's file was not closed with the group"
