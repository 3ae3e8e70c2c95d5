"""Where verification runs execute: in this process, on a local process pool, or on a Ray cluster.

An executor runs independent :class:`~swarmdeck.console.sandbox.verification.RunTask`\\ s
with :func:`~swarmdeck.console.sandbox.verification.run_task` (or another task function ``fn``: a sweep's
points) and returns their
results in task order, whatever order they finished in, so every executor gives
the same report. ``run(tasks, on_done, cancelled)`` calls ``on_done(index,
result, finished_count)`` as runs finish and stops starting runs once
``cancelled()`` is true (results of runs never started are None). Each run's
sandbox is built inside the worker, so Ray workers confine user code too.

A task whose ``paced`` attribute is true (a verification's paced runs, :attr:`RunTask.paced`) ticks in real time
and mostly waits: the pool and Ray run it beside the computing runs (a worker of its own, unpinned; on Ray a task
that asks for no CPU), so a 60 s paced run no longer holds one of the ``workers`` for 60 s while the others idle
(bench/RESULTS.md "verification that scales").
"""
from __future__ import annotations

import multiprocessing
import os
import queue
import threading
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, ThreadPoolExecutor, wait
from contextlib import ExitStack, contextmanager
from typing import Any

from swarmdeck.console.sandbox.cores import claim_core
from swarmdeck.console.sandbox.verification import RunTask, run_task

OnDone = Callable[[int, dict[str, Any], int], None]
#: most workers a pool starts for paced tasks (each mostly waits for the clock)
MAX_PACED_WORKERS = 4


def _paced(tasks: Sequence[Any]) -> list[bool]:
    """Which tasks tick in real time (their ``paced`` attribute; tasks without one compute)."""
    return [bool(getattr(task, "paced", False)) for task in tasks]
#: what runs one task in a worker (default :func:`run_task`; a sweep's ``console.sweep.runs.run_point``): a
#: module-level function of one picklable task returning a JSON-ready dict
TaskFn = Callable[[Any], dict[str, Any]]


class SerialExecutor:
    """Every run one after the other in this process (each still in its own sandboxed child)."""

    name = "serial"

    def run(self, tasks: Sequence[RunTask], on_done: OnDone, cancelled: Callable[[], bool],
            fn: TaskFn = run_task) -> list[dict | None]:
        results: list[dict | None] = [None] * len(tasks)
        for k, task in enumerate(tasks):
            if cancelled():
                break
            results[k] = result = fn(task)
            on_done(k, result, k + 1)
        return results


def _init_worker(parent: int, cpus: Any) -> None:
    """Pool initializer: the worker dies with the process that started the pool (also when that one is
    kill -9'd: its fork server and jails follow, see :mod:`.zygote`); with ``cpus`` (a queue of core
    numbers), it — and the fork server and jails it starts — runs on one core."""
    from swarmdeck.console.sandbox.namespaces import die_with_parent

    die_with_parent(parent)
    if cpus is None:
        return
    try:
        cpu = cpus.get(timeout=5)
    except queue.Empty:
        return
    try:
        os.sched_setaffinity(0, {cpu})
    except OSError:
        pass


class LocalPoolExecutor:
    """A pool of ``workers`` local processes (default: the number of cores); no service needed.

    The workers end with the process that started them, even when it is kill -9'd (``PR_SET_PDEATHSIG``;
    a pool lives inside one :meth:`run` call, in the calling thread). ``pin``: each worker runs on a core of its own (worker k on core k mod cores), with the
    sandboxed script it drives. The trusted loop and the script take turns every tick, so
    sharing one core keeps both processes' caches warm and their wake-ups local, and two
    workers never fight over one core (bench/RESULTS.md "verification").
    """

    name = "local"

    def __init__(self, workers: int | None = None, pin: bool = True) -> None:
        if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int) or workers < 1):
            raise ValueError(f"workers must be a positive integer, got {workers!r}")
        self.workers = workers or os.cpu_count() or 1
        self.pin = pin
        self._lock = threading.Lock()  # guards the kept pools: several verification threads share one executor
        self._holders = 0  # open kept() blocks (any thread)
        self._kept: ProcessPoolExecutor | None = None  # the computing workers, while kept
        self._kept_aside: ProcessPoolExecutor | None = None  # the paced tasks' workers, while kept (started when needed)
        # the one thread that submits to the kept pools: a worker process is started by the thread whose submit
        # needs it and dies with that thread (PR_SET_PDEATHSIG, _init_worker), so it must outlive every kept run
        self._submitter: ThreadPoolExecutor | None = None

    def _pool(self, workers: int, pin: bool | None = None) -> ProcessPoolExecutor:
        context = multiprocessing.get_context("spawn")  # no fork of a threaded caller (the portal)
        cpus = None
        if (self.pin if pin is None else pin) and hasattr(os, "sched_getaffinity"):
            cores = sorted(os.sched_getaffinity(0))
            cpus = context.Queue()
            for k in range(workers):
                cpus.put(cores[k % len(cores)])
        return ProcessPoolExecutor(max_workers=workers, mp_context=context, initializer=_init_worker,
                                   initargs=(os.getpid(), cpus))

    @contextmanager
    def kept(self) -> Iterator[LocalPoolExecutor]:
        """Keep one pool of ``workers`` processes (and their warm fork servers) — and, once a paced task came, the
        paced tasks' workers — for every :meth:`run` inside the block, from any thread: the falsifier's generations
        are many small batches, and the portal's verification threads run one verification after another on the
        same executor (``console/portal/workers.py``). Without it each :meth:`run` starts its pools (Python,
        numpy, swarmdeck and a fork server per worker: ≈ 0.5–1 s of CPU each, bench/RESULTS.md "verification
        queue"). Blocks may nest and overlap across threads: the pools end with the last one."""
        with self._lock:
            self._holders += 1
            if self._kept is None:
                self._submitter = ThreadPoolExecutor(1, thread_name_prefix="swarmdeck-pool-submit")
                self._kept = self._pool(self.workers)
        try:
            yield self
        finally:
            with self._lock:
                self._holders -= 1
                ending: list[ProcessPoolExecutor | ThreadPoolExecutor | None] = []
                if not self._holders:
                    ending = [self._kept, self._kept_aside, self._submitter]
                    self._kept = self._kept_aside = self._submitter = None
            for pool in ending:
                if pool is not None:
                    pool.shutdown(wait=True, cancel_futures=True)

    def _pools(self, computing: int, paced: int, stack: ExitStack) -> tuple[
            ProcessPoolExecutor | None, ProcessPoolExecutor | None, ThreadPoolExecutor | None]:
        """The pools for ``computing`` computing and ``paced`` paced tasks and the thread to submit to them from:
        the kept ones (the paced one started on first need and kept with them), else new ones that end with
        ``stack`` (submitted to from this thread: None)."""
        with self._lock:
            pool, aside, submitter = self._kept, self._kept_aside, self._submitter
            if pool is not None and paced and aside is None:
                aside = self._kept_aside = self._pool(MAX_PACED_WORKERS, pin=False)
        if pool is None:
            submitter = None
            if computing:
                pool = stack.enter_context(self._pool(min(self.workers, computing)))
            if paced:
                aside = stack.enter_context(self._pool(min(paced, MAX_PACED_WORKERS), pin=False))
        return pool, aside, submitter

    def run(self, tasks: Sequence[RunTask], on_done: OnDone, cancelled: Callable[[], bool],
            fn: TaskFn = run_task) -> list[dict | None]:
        results: list[dict | None] = [None] * len(tasks)
        if not tasks:
            return results
        paced = _paced(tasks)
        computing = len(tasks) - sum(paced)
        with ExitStack() as stack:
            # the paced tasks' own workers (aside) wait for the clock, beside the computing ones
            pool, aside, submitter = self._pools(computing, len(tasks) - computing, stack)
            order = sorted(range(len(tasks)), key=lambda k: not paced[k])  # the long paced runs start first
            pending: dict[Future, int] = {}
            for k in order:
                target = aside if paced[k] else pool
                assert target is not None
                if submitter is None:
                    pending[target.submit(fn, tasks[k])] = k
                else:  # kept pools: their workers are started by the submitting thread, which lives as long as they
                    pending[submitter.submit(target.submit, fn, tasks[k]).result(timeout=600)] = k
            return self._run_on(pending, on_done, cancelled, results)

    @staticmethod
    def _run_on(pending: dict[Future, int], on_done: OnDone, cancelled: Callable[[], bool],
                results: list[dict | None]) -> list[dict | None]:
        finished = 0
        while pending:
            done, _ = wait(pending, timeout=0.5, return_when=FIRST_COMPLETED)
            for future in done:
                k = pending.pop(future)
                if future.cancelled():
                    continue
                results[k] = result = future.result()
                finished += 1
                on_done(k, result, finished)
            if cancelled():  # running tasks see the cancel file and stop within a tick
                for future in pending:
                    future.cancel()
        return results


def _on_a_core(fn: TaskFn, task: Any) -> dict[str, Any]:
    """A Ray task: this worker process on a core no other claims (:func:`~.cores.claim_core`, kept for its life),
    then ``fn(task)`` — what :class:`LocalPoolExecutor` does with ``pin``."""
    claim_core()
    return fn(task)


class RayExecutor:
    """The same tasks on a Ray cluster: ``address`` "auto" (a running cluster), "local" (start one
    here with ``num_cpus``) or ``ray://host:port``. Needs ``pip install 'swarmdeck[ray]'`` and
    swarmdeck installed on every node."""

    name = "ray"

    def __init__(self, address: str = "auto", num_cpus: int | None = None) -> None:
        try:
            import ray
        except ImportError as exc:
            raise RuntimeError("Ray is not installed: pip install 'swarmdeck[ray]'") from exc
        self.ray = ray
        self.address, self.num_cpus = address, num_cpus

    def _connect(self) -> None:
        ray = self.ray
        if ray.is_initialized():
            return
        kwargs: dict[str, Any] = {"include_dashboard": False, "log_to_driver": False, "configure_logging": False}
        if self.address == "local":
            ray.init(num_cpus=self.num_cpus, **kwargs)
        else:
            ray.init(address=self.address, **kwargs)

    def run(self, tasks: Sequence[RunTask], on_done: OnDone, cancelled: Callable[[], bool],
            fn: TaskFn = run_task) -> list[dict | None]:
        ray = self.ray
        self._connect()
        computing = ray.remote(num_cpus=1, max_retries=0)(_on_a_core)  # as the local pool's workers: a core each
        waiting = ray.remote(num_cpus=0, max_retries=0)(fn)  # real-time runs mostly wait, beside the computing ones
        paced = _paced(tasks)
        refs = {(waiting.remote(tasks[k]) if paced[k] else computing.remote(fn, tasks[k])): k
                for k in sorted(range(len(tasks)), key=lambda k: not paced[k])}
        results: list[dict | None] = [None] * len(tasks)
        finished = 0
        while refs:
            if cancelled():
                for ref in refs:
                    ray.cancel(ref, force=True)
                break
            done, _ = ray.wait(list(refs), num_returns=1, timeout=0.5)
            for ref in done:
                k = refs.pop(ref)
                try:
                    results[k] = ray.get(ref)
                except ray.exceptions.RayError as exc:  # e.g. a node without bubblewrap: infrastructure, not a verdict
                    for other in refs:
                        ray.cancel(other, force=True)
                    raise RuntimeError(f"a Ray worker could not run its task (a verification or sweep run): {exc}") from exc
                finished += 1
                on_done(k, results[k], finished)
        return results
