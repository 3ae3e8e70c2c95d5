"""Paced runs (real time: they mostly wait for the clock) run beside the computing runs, in a worker of their own,
instead of holding one of the pool's workers for their whole duration (console/sandbox/executors.py)."""
from __future__ import annotations

import os
from dataclasses import dataclass

from swarmdeck.console.sandbox.executors import LocalPoolExecutor, SerialExecutor


@dataclass(frozen=True)
class Task:
    index: int
    paced: bool


def where(task: Task) -> dict:
    """What a worker reports of the task it ran (module level: the spawned workers import it)."""
    return {"index": task.index, "paced": task.paced, "pid": os.getpid()}


TASKS = [Task(0, False), Task(1, True), Task(2, False), Task(3, False)]


def test_a_paced_task_runs_in_a_worker_beside_the_pool_and_results_keep_the_task_order() -> None:
    done: list[int] = []
    results = LocalPoolExecutor(1, pin=False).run(TASKS, lambda k, result, n: done.append(k), lambda: False, fn=where)
    assert [r["index"] for r in results] == [0, 1, 2, 3] and sorted(done) == [0, 1, 2, 3]
    computing = {r["pid"] for r in results if not r["paced"]}
    assert len(computing) == 1, "one worker ran every computing task"
    assert results[1]["pid"] not in computing, "the paced task held the pool's only worker"


def test_the_serial_executor_runs_every_task_here_in_order() -> None:
    results = SerialExecutor().run(TASKS, lambda k, result, n: None, lambda: False, fn=where)
    assert [r["index"] for r in results] == [0, 1, 2, 3] and {r["pid"] for r in results} == {os.getpid()}
