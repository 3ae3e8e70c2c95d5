"""bench/harness.py is the one timing harness: median and worst case, markdown rows, this interpreter for
child processes; every bench uses it and none pins BLAS itself or names an interpreter path."""
from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[2] / "bench"
sys.path.insert(0, str(BENCH))

import harness  # noqa: E402


def test_timing_median_worst_and_row():
    t = harness.timing([0.003, 0.001, 0.002, 0.010])
    assert t.median == pytest.approx(0.0025) and t.worst == 0.010
    assert t.ms(2) == "2.50 (10.00)"
    assert harness.table_row(12, t, 1.5, "x") == "| 12 | 2.500 (10.000) | 1.500 | x |"
    assert harness.table_header(["N", "ms"]) == "| N | ms |\n| --- | ---: |"
    with pytest.raises(ValueError):
        harness.timing([])


def test_measure_calls_warmup_then_repeats_on_the_chosen_clock():
    calls = []
    t = harness.measure(lambda: calls.append(1), 5, clock="thread", warmup=2)
    assert len(calls) == 7 and len(t.samples) == 5 and t.clock == "thread"
    assert all(s >= 0 for s in t.samples)
    seconds, out = harness.timed(lambda a, b: a + b, 2, 3)
    assert out == 5 and seconds >= 0
    with pytest.raises(ValueError):
        harness.measure(lambda: None, 0)


def test_children_run_on_this_interpreter():
    assert harness.python() == [sys.executable]
    assert harness.swarmdeck_cli()[0] == sys.executable


@pytest.mark.parametrize("path", sorted(BENCH.glob("bench_*.py")), ids=lambda p: p.name)
def test_every_bench_uses_the_harness(path: Path):
    text = path.read_text()
    assert re.search(r"^import harness\b", text, re.MULTILINE), "import harness first (BLAS, timing, table)"
    assert "NUM_THREADS" not in text, "BLAS is pinned by the harness"
    assert not re.search(r"/(usr|opt|work|home)/\S*python", text), "no interpreter path: this one (sys.executable)"
