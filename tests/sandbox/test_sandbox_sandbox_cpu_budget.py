"""The sandbox's per-tick budget charges the script's CPU time (its cgroup's count), not wall time: a script
that waits (sleeps, or is not scheduled on a loaded machine) does not overrun, one that computes does; a wall
backstop still bounds every tick, and a late answer is still a missed tick (issue 24)."""
import textwrap

import pytest

from swarmdeck.console.sandbox import cgroups
from swarmdeck.console.sandbox.confinement import SandboxLimits, probe
from swarmdeck.console.sandbox.plant import ArenaPlant
from swarmdeck.console.sandbox.run import run_sandboxed
from swarmdeck.devices.arena import Arena

pytestmark = pytest.mark.skipif(probe() is not None or cgroups.probe() is not None,
                                reason=f"no confinement or cgroup here: {probe() or cgroups.probe()}")


def run(tmp_path, body, limits):
    script = tmp_path / "script.py"
    script.write_text(textwrap.dedent(body))
    return run_sandboxed(script, lambda n, ic: ArenaPlant(Arena(n, initial_conditions=ic, duration=60.0)),
                         n_robots=2, duration=60.0, limits=limits)


SLEEPS = """
    import time
    def experiment(arena):
        for _ in range(3):
            arena.step()
            time.sleep(1.0)  # wall time, no CPU time: 2.5 x the budget
        arena.step()
"""

SPINS = """
    import time
    def experiment(arena):
        arena.step()
        start = time.thread_time()
        while time.thread_time() - start < 1.0:  # CPU time: 2.5 x the budget
            pass
        arena.step()
        arena.step()
"""


def test_a_script_that_sleeps_does_not_overrun_its_cpu_budget(tmp_path):
    out = run(tmp_path, SLEEPS, SandboxLimits(tick_s=0.4, max_overruns=2))
    assert out.ended_by == "script", out.error_line
    assert (out.ticks, out.overruns) == (4, 0)
    wall = run(tmp_path, SLEEPS, SandboxLimits(tick_s=0.4, max_overruns=2, tick_clock="wall"))
    assert wall.ended_by == "overruns"  # the same script, charged wall time (before: always)


def test_a_script_that_computes_overruns_and_its_late_answer_is_dropped(tmp_path):
    out = run(tmp_path, SPINS, SandboxLimits(tick_s=0.4, max_overruns=5))
    assert out.ended_by == "script" and out.overruns >= 1
    assert out.ticks == out.overruns + 2  # 1 good, the missed ones (the late answer dropped), 1 good after it


def test_the_wall_backstop_bounds_a_tick_that_uses_no_cpu(tmp_path):
    out = run(tmp_path, SLEEPS, SandboxLimits(tick_s=0.4, tick_wall_s=0.6, max_overruns=1))
    assert out.ended_by == "overruns" and "CPU time" in out.error_line and "0.6 s of wall time" in out.error_line
