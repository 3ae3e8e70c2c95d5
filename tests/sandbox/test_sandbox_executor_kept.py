"""A local pool kept across runs and threads (console/sandbox/executors.py ``LocalPoolExecutor.kept``): the portal's
verification threads run one verification after another on one executor, so its workers — computing and paced —
start once, not once per verification (each worker is a new Python, numpy, swarmdeck and fork server)."""
from __future__ import annotations

import os
import threading
from dataclasses import dataclass

from swarmdeck.console.sandbox import executors
from swarmdeck.console.sandbox.executors import LocalPoolExecutor


@dataclass(frozen=True)
class Task:
    index: int
    paced: bool


def where(task: Task) -> dict:
    """The worker that ran the task (module level: the spawned workers import it)."""
    return {"index": task.index, "paced": task.paced, "pid": os.getpid()}


TASKS = [Task(0, True), Task(1, False), Task(2, False)]


def pids(results: list[dict | None], paced: bool) -> set[int]:
    return {r["pid"] for r in results if r is not None and r["paced"] == paced}


def test_threads_share_one_kept_pool_its_paced_worker_too_and_it_ends_with_the_last_of_them(monkeypatch) -> None:
    # one paced worker (of up to MAX_PACED_WORKERS): a second one may start while the first is reported idle
    monkeypatch.setattr(executors, "MAX_PACED_WORKERS", 1)
    executor = LocalPoolExecutor(1, pin=False)
    results: dict[int, list[dict | None]] = {}
    inside = threading.Barrier(2, timeout=120)  # both threads hold the pool before either runs or leaves
    leave = threading.Event()

    def verification(k: int) -> None:
        with executor.kept():
            inside.wait()
            results[k] = executor.run(TASKS, lambda j, r, n: None, lambda: False, fn=where)
            if k == 0:
                leave.wait(120)  # the first thread stays until the second has left (its thread has ended)
                results[2] = executor.run(TASKS, lambda j, r, n: None, lambda: False, fn=where)

    threads = [threading.Thread(target=verification, args=(k,), daemon=True) for k in (0, 1)]
    for t in threads:
        t.start()
    threads[1].join(180)
    assert not threads[1].is_alive(), "the second verification thread did not end within 180 s"
    assert executor._kept is not None, "the pool ended while another thread still held it"
    leave.set()
    threads[0].join(180)
    assert not threads[0].is_alive(), "the first verification thread did not end within 180 s"
    # a worker started for a thread that has ended must not have died with it (BrokenProcessPool: no results[2])
    assert sorted(results) == [0, 1, 2] and all(r["index"] == k for rs in results.values() for k, r in enumerate(rs) if r)
    computing = set().union(*(pids(r, False) for r in results.values()))
    paced = set().union(*(pids(r, True) for r in results.values()))
    assert len(computing) == 1, "every run's computing tasks ran on the one kept worker"
    assert len(paced) == 1, "the paced tasks' worker is kept too (it was started per run)"
    assert not computing & paced, "the paced tasks ran beside the computing worker"
    assert executor._kept is None and executor._kept_aside is None, "the pools end with the last block"
