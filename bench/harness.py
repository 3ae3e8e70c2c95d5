"""The one timing harness every bench uses: BLAS pinning, median and worst case, a same-process baseline,
the machine line and the markdown table rows of ``bench/RESULTS.md``, and the interpreter for child processes.

Import it first in a bench (``import harness`` works because a bench runs as ``python bench/bench_x.py``,
which puts ``bench/`` on ``sys.path``): importing it pins BLAS/OpenMP to one thread *before* numpy loads
(threaded BLAS on a busy 2-core machine spin-waits; the suite's ``tests/conftest.py`` does the same).

* :func:`measure` — run ``fn`` ``repeats`` times on a chosen clock (``"wall"``: ``perf_counter``;
  ``"cpu"``: this process's CPU time; ``"thread"``: the calling thread's CPU time, robust to other
  processes on a shared machine) and return a :class:`Timing` with the median and the worst case.
* :func:`timed` — one call's time and its result, for loops that time a stage and use what it returned.
* :func:`baseline` — a fixed numpy workload (sort 10⁵ floats ×10) timed in the same process, so numbers
  from different machines and loads can be compared as ratios.
* :func:`machine` — the one-line description of the machine, Python, numpy, BLAS threads and load.
* :func:`table_header` / :func:`table_row` — markdown table lines as ``RESULTS.md`` quotes them.
* :func:`python` / :func:`swarmdeck_cli` — argv prefixes for child processes: always this interpreter
  (``sys.executable``), never a hard-coded path.
"""
from __future__ import annotations

import os

#: The variables pinned to one thread (set only where the caller has not chosen otherwise).
BLAS_VARS: tuple[str, ...] = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def pin_blas(threads: int = 1) -> None:
    """Set each of :data:`BLAS_VARS` to ``threads`` unless already set (effective only before numpy loads)."""
    for var in BLAS_VARS:
        os.environ.setdefault(var, str(threads))


pin_blas()

import platform  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable, Iterable, Sequence  # noqa: E402
from dataclasses import dataclass  # noqa: E402
from typing import TypeVar  # noqa: E402

import numpy as np  # noqa: E402

T = TypeVar("T")

#: Clock name → the function returning its reading, s.
CLOCKS: dict[str, Callable[[], float]] = {
    "wall": time.perf_counter,
    "cpu": time.process_time,
    "thread": time.thread_time,
}


@dataclass(frozen=True)
class Timing:
    """Samples of one measurement, s, and the clock they were taken on."""

    samples: tuple[float, ...]
    clock: str = "wall"

    @property
    def median(self) -> float:
        """Median sample, s."""
        return float(statistics.median(self.samples))

    @property
    def worst(self) -> float:
        """Largest sample, s (the worst case)."""
        return float(max(self.samples))

    @property
    def median_ms(self) -> float:
        """Median sample, ms."""
        return 1e3 * self.median

    @property
    def worst_ms(self) -> float:
        """Largest sample, ms."""
        return 1e3 * self.worst

    def percentile_ms(self, q: float) -> float:
        """The ``q``-th percentile (0–100) of the samples, ms."""
        return 1e3 * float(np.percentile(self.samples, q))

    def ms(self, digits: int = 3) -> str:
        """``"median (worst)"`` in ms, as the tables quote them."""
        return f"{self.median_ms:.{digits}f} ({self.worst_ms:.{digits}f})"


def timing(samples: Iterable[float], clock: str = "wall") -> Timing:
    """A :class:`Timing` of samples (s) taken elsewhere (a loop that times several stages at once)."""
    s = tuple(float(x) for x in samples)
    if not s:
        raise ValueError("timing needs at least one sample")
    return Timing(s, clock)


def measure(fn: Callable[[], object], repeats: int, *, clock: str = "wall", warmup: int = 0) -> Timing:
    """Call ``fn`` ``warmup`` times untimed, then ``repeats`` times, each timed alone on ``clock``
    (one of :data:`CLOCKS`)."""
    if repeats < 1:
        raise ValueError(f"repeats must be >= 1, got {repeats}")
    now = CLOCKS[clock]
    for _ in range(warmup):
        fn()
    out = []
    for _ in range(repeats):
        t0 = now()
        fn()
        out.append(now() - t0)
    return Timing(tuple(out), clock)


def timed(fn: Callable[..., T], *args: object, clock: str = "cpu") -> tuple[float, T]:
    """``(seconds on clock, fn(*args))`` for one call; process CPU time by default (robust to the other
    processes on a shared VM)."""
    now = CLOCKS[clock]
    t0 = now()
    out = fn(*args)
    return now() - t0, out


def _sort_workload() -> None:
    a = np.random.default_rng(0).normal(size=100_000)
    for _ in range(10):
        np.sort(a)


def baseline(repeats: int = 30, clock: str = "thread") -> Timing:
    """The same-process baseline: a fixed numpy workload (sort 10⁵ normal floats ×10) on ``clock``."""
    return measure(_sort_workload, repeats, clock=clock)


def cpu_name() -> str:
    """The CPU's model name (``/proc/cpuinfo``), else what :mod:`platform` knows."""
    try:
        with open("/proc/cpuinfo") as f:
            return next(line.split(":", 1)[1].strip() for line in f if line.startswith("model name"))
    except (OSError, StopIteration):
        return platform.processor() or platform.machine()


def machine() -> str:
    """One line: cores, CPU, Python, numpy, BLAS threads, load average."""
    cpu = cpu_name()
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    return (f"machine: {os.cpu_count()} cores, {cpu}; Python {platform.python_version()}; numpy {np.__version__}; "
            f"BLAS threads {os.environ.get('OPENBLAS_NUM_THREADS', '?')}; load average {load:.1f}")


def table_header(columns: Sequence[str], numeric: Sequence[bool] | None = None) -> str:
    """The header and the alignment line of a markdown table (numeric columns right-aligned;
    by default every column but the first)."""
    num = list(numeric) if numeric is not None else [False] + [True] * (len(columns) - 1)
    if len(num) != len(columns):
        raise ValueError("numeric must have one entry per column")
    return "| " + " | ".join(columns) + " |\n| " + " | ".join("---:" if n else "---" for n in num) + " |"


def table_row(*cells: object) -> str:
    """One markdown table row; floats are written with 3 decimals, :class:`Timing` as ``median (worst)`` ms."""
    def fmt(c: object) -> str:
        if isinstance(c, Timing):
            return c.ms()
        if isinstance(c, float):
            return f"{c:.3f}"
        return str(c)
    return "| " + " | ".join(fmt(c) for c in cells) + " |"


def python() -> list[str]:
    """argv prefix for a child Python process: this interpreter."""
    return [sys.executable]


def swarmdeck_cli() -> list[str]:
    """argv prefix for ``swarmdeck …`` in a child process, through this interpreter."""
    return [sys.executable, "-c", "import sys; from swarmdeck.console.cli import main; sys.exit(main())"]
