"""The sandbox's tick loop (issue 24, item 4): an answer tagged with another tick's number is a missed tick (robots
stopped for it, simulated time advances, counted); a late answer to poses already counted missed is dropped; a
cancel ends the run after the very plant step it was seen at — nothing the script answers keeps a run going."""
import textwrap

import numpy as np
import pytest

from swarmdeck.console.sandbox.confinement import SandboxLimits, probe
from swarmdeck.console.sandbox.plant import ArenaPlant
from swarmdeck.console.sandbox.run import run_sandboxed
from swarmdeck.devices.arena import Arena
from swarmdeck.devices.simulator import ArenaConfig

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")
DT = 0.033


def plant(n, initial):
    return ArenaPlant(Arena(n, initial_conditions=initial, config=ArenaConfig(seed=1), duration=60.0))


def run(tmp_path, body, **kwargs):
    script = tmp_path / "script.py"
    script.write_text(textwrap.dedent(body))
    return run_sandboxed(script, plant, n_robots=2, duration=60.0, **kwargs)


def test_answers_for_another_tick_are_missed_ticks_and_time_goes_on(tmp_path):
    out = run(tmp_path, """
        import numpy as np
        def experiment(arena):
            for _ in range(4):  # four good ticks driving forward
                arena.set_unicycle(np.full(arena.n, 0.1), np.zeros(arena.n))
                arena.step()
            while True:  # then every answer carries a tick number from the future
                arena.backend._k += 7
                arena.set_unicycle(np.full(arena.n, 0.1), np.zeros(arena.n))
                arena.step()
    """, limits=SandboxLimits(max_overruns=3))
    assert out.ended_by == "overruns" and "an answer for another tick" in out.error_line
    assert (out.ticks, out.overruns) == (7, 3)
    arena = out.plant.arena
    assert arena.time == pytest.approx(7 * DT)  # the stale answers did not hold simulated time
    assert np.all(arena.last_safe == 0.0)  # those ticks stopped the robots


def test_a_late_answer_is_counted_once_and_then_dropped(tmp_path):
    out = run(tmp_path, """
        import time
        import numpy as np
        def experiment(arena):
            arena.step()
            time.sleep(0.7)  # misses two 0.3 s budgets; its answer then arrives late
            arena.step()
            arena.step()
    """, limits=SandboxLimits(tick_s=0.3, max_overruns=5, tick_clock="wall"))  # (CPU time: test_sandbox_sandbox_cpu_budget)
    assert out.ended_by == "script" and out.overruns >= 1  # (two 0.3 s budgets fit in 0.7 s; a loaded machine may see one)
    assert out.ticks == out.overruns + 2  # 1 good, the missed ones (the late answer dropped), 1 good after it


def test_a_cancel_ends_the_run_after_the_plant_step_it_was_seen_at(tmp_path):
    seen = {}

    def cancelled():
        arena = getattr(seen.get("out"), "arena", None)
        return arena is not None and arena.time >= 3 * DT - 1e-9

    def watching_plant(n, initial):
        seen["out"] = plant(n, initial)
        return seen["out"]

    script = tmp_path / "script.py"
    script.write_text("def experiment(arena):\n    while True:\n        arena.step()\n")
    out = run_sandboxed(script, watching_plant, n_robots=2, duration=60.0, cancelled=cancelled)
    assert out.ended_by == "cancelled" and out.ticks == 3  # every 16 exchanges before: 16 ticks
