"""Scripts run at once in threads of one process (the regions of a shared floor) each run as ``__main__`` and
leave the process's own ``__main__`` as it was.

Before: each ran through ``runpy.run_path(run_name="__main__")``, which swaps ``sys.modules["__main__"]`` for the
script's module and swaps the saved one back at the end. Two at once, the second saved the first's module and
put it back last, so the first script stayed the process's ``__main__``: a later ``multiprocessing`` spawn (the
verification pool) ran that script in its children, which never answered, and the pool's shutdown waited for
them forever (a CI run hung on it for an hour).
"""
from __future__ import annotations

import sys
import threading
from pathlib import Path

from swarmdeck.devices.runner import run_experiment

# the scripts meet through the test's events (a module both import): A starts, B starts, A ends, then B ends —
# the order in which runpy's save-and-restore left A as the process's __main__
SCRIPT = """
import sys
from swarmdeck_concurrent_main_events import EVENTS

EVENTS["{me}_started"].set()
EVENTS["{wait}"].wait(60)
SEEN = __name__
from swarmdeck.devices import Arena

def experiment(arena):
    EVENTS["{me}_name"] = __name__
"""


def test_two_scripts_at_once_each_run_as_main_and_leave_the_process_main_alone(tmp_path: Path) -> None:
    import types

    events = {k: threading.Event() for k in ("a_started", "b_started", "a_done")}
    shared = types.ModuleType("swarmdeck_concurrent_main_events")
    shared.EVENTS = events  # type: ignore[attr-defined]
    sys.modules[shared.__name__] = shared
    main_before = sys.modules["__main__"]
    try:
        a, b = tmp_path / "a.py", tmp_path / "b.py"
        a.write_text(SCRIPT.format(me="a", wait="b_started"))
        b.write_text(SCRIPT.format(me="b", wait="a_done"))
        results: dict[str, object] = {}

        def run(name: str, path: Path) -> None:
            results[name] = run_experiment(path, n_robots=2, duration=0.1)
            if name == "a":
                events["a_done"].set()

        threads = [threading.Thread(target=run, args=("a", a)), threading.Thread(target=run, args=("b", b))]
        threads[0].start()
        assert events["a_started"].wait(60), "script a did not start"
        threads[1].start()
        for t in threads:
            t.join(120)
        assert not any(t.is_alive() for t in threads), "a script run did not end"
        assert sys.modules["__main__"] is main_before
        assert events["a_name"] == events["b_name"] == "__main__"  # type: ignore[comparison-overlap]
        for name in ("a", "b"):
            assert results[name].error is None, results[name].error  # type: ignore[attr-defined]
    finally:
        sys.modules.pop(shared.__name__, None)
        sys.modules["__main__"] = main_before
