"""A behaviour script that hangs is abandoned for the tick, robots stop, the panel says why, the loop goes on.

Deterministic: the script blocks on an Event the test holds, so it never returns by itself; what is
asserted is counts of abandoned ticks and waits, never how long anything took.
"""
from __future__ import annotations

import sys

import numpy as np
import pytest

from swarmdeck.console.runtime.deadline import DeadlineCaller, TickBudgetExceeded
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig

HANGING = ("import threading\n"
           "import numpy as np\n"
           "GATE = threading.Event()\n"
           "def behaviour(poses, t):\n"
           "    if t > 0.05:\n"
           "        GATE.wait()\n"
           "    return np.tile([0.1, 0.0], (len(poses), 1))\n")


def test_a_hanging_script_is_abandoned_every_tick_and_waited_for_once(tmp_path) -> None:
    path = tmp_path / "hang.py"
    path.write_text(HANGING)
    # A generous budget: the script either returns at once or never, so nothing depends on speed.
    loop = ControlLoop(LoopConfig(n_robots=4, seed=3, behaviour=f"script:{path}", script_budget=0.5))
    script = loop._behaviour
    ok = [loop.tick() for _ in range(2)]  # t = 0, 0.033: returns
    assert not ok[-1].stopped and not ok[-1].alerts
    hung = [loop.tick() for _ in range(20)]  # t > 0.05: never returns
    for f in hung:
        assert f.stopped and np.all(f.v == 0.0) and np.all(f.w == 0.0)
        assert any("tick budget" in a or "earlier tick" in a for a in f.alerts), f.alerts
    assert any("robots stopped" in a for a in hung[-1].alerts)
    assert script.caller.abandoned == 20 and script.caller.timed_out == 1 and script.caller.skipped == 19
    assert loop.errors["behaviour"] == 20
    assert "20 ticks abandoned" in loop.tick().health["script"]
    script.func.__globals__["GATE"].set()  # the script returns at last: its late result is discarded
    assert script.caller.wait_idle(10.0) and script.caller.late == 1
    back = loop.tick()
    assert not back.stopped and not back.alerts and np.abs(back.v).max() > 0
    assert script.caller.abandoned == 21


def test_switching_away_from_a_hung_script_gives_control_back(tmp_path) -> None:
    path = tmp_path / "hang.py"
    path.write_text(HANGING.replace("t > 0.05", "True"))
    loop = ControlLoop(LoopConfig(n_robots=4, seed=3, behaviour=f"script:{path}", script_budget=0.2))
    script = loop._behaviour
    assert loop.tick().stopped
    loop.set_behaviour("rendezvous")
    f = loop.tick()
    assert f.behaviour == "rendezvous" and not f.stopped and not f.alerts
    script.func.__globals__["GATE"].set()
    assert script.caller.wait_idle(10.0)


def test_the_default_budget_leaves_the_loop_its_period() -> None:
    assert LoopConfig().script_budget_s == pytest.approx(0.5 * 0.033)
    assert LoopConfig(dt=0.1).script_budget_s == pytest.approx(0.05)
    assert LoopConfig(script_budget=0.01).script_budget_s == 0.01
    for bad in (0.0, -1.0, float("nan"), 0.6):
        with pytest.raises(ValueError, match="script_budget"):
            LoopConfig(script_budget=bad)


def test_deadline_caller_returns_results_and_reraises_errors() -> None:
    caller = DeadlineCaller()
    assert caller.call(lambda a, b: a + b, 2, 3, budget=10.0) == 5
    with pytest.raises(KeyError, match="nope"):
        caller.call(lambda: {}["nope"], budget=10.0)
    with pytest.raises(RuntimeError, match="SystemExit"):  # a script's sys.exit() never ends the loop
        caller.call(sys.exit, 3, budget=10.0)
    assert caller.abandoned == 0 and caller.calls == 3 and not caller.busy
    caller.close()
    with pytest.raises(RuntimeError, match="closed"):
        caller.call(lambda: 1, budget=1.0)


def test_deadline_caller_abandons_without_waiting_while_a_call_hangs() -> None:
    import threading

    gate = threading.Event()
    caller = DeadlineCaller()
    with pytest.raises(TickBudgetExceeded, match="tick budget"):
        caller.call(gate.wait, budget=0.05)
    for _ in range(5):
        with pytest.raises(TickBudgetExceeded, match="earlier tick"):
            caller.call(lambda: 1, budget=10.0)
    assert (caller.timed_out, caller.skipped, caller.calls) == (1, 5, 1) and caller.busy
    gate.set()
    assert caller.wait_idle(10.0) and caller.late == 1 and not caller.busy
    assert caller.call(lambda: 7, budget=10.0) == 7


def test_an_idle_worker_ends_with_its_behaviour(tmp_path) -> None:
    import gc

    path = tmp_path / "quick.py"
    path.write_text(HANGING.replace("t > 0.05", "False"))
    loop = ControlLoop(LoopConfig(n_robots=3, seed=1, behaviour=f"script:{path}", script_budget=0.5))
    loop.tick()
    worker = loop._behaviour.caller._thread
    assert worker is not None and worker.is_alive()
    loop.set_behaviour("coverage")  # the old script is closed and dropped
    gc.collect()
    worker.join(10.0)
    assert not worker.is_alive()
