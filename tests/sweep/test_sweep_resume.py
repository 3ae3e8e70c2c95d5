"""An interrupted sweep continues: a Ray cluster gone mid-sweep (the executor fails) and a cancel both stop it cleanly,
name the runs not done and keep the finished ones; the same sweep run again runs only the rest."""
import csv
from dataclasses import dataclass

import pytest

from swarmdeck.console.sandbox.bundle import ScriptBundle
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.executors import SerialExecutor
from swarmdeck.console.sandbox.verification import VerificationConfig
from swarmdeck.console.sweep.campaign import SweepIncomplete, SweepSpec, run_sweep

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")

SCRIPT = b"""
from swarmdeck.devices import params
p = params(gain=1.0)

def experiment(arena):
    while True:
        x = arena.positions()
        arena.set_velocities(-p.gain * (x - x.mean(axis=0)))
        arena.step()
"""


class ClusterGone(SerialExecutor):
    """The serial executor whose cluster goes away after ``after`` runs (as RayExecutor raises when a node is lost)."""

    name = "ray"

    def __init__(self, after: int) -> None:
        self.after = after

    def run(self, tasks, on_done, cancelled, fn):
        def done(k, result, finished):
            on_done(k, result, finished)
            if finished >= self.after:
                raise RuntimeError("a Ray worker could not run the task: the cluster at 10.0.0.7:6379 is gone")

        return super().run(tasks, done, cancelled, fn)


@dataclass
class CancelAfter:
    """A cancel event set once ``after`` runs finished (as Ctrl-C in the CLI, or a portal cancel)."""

    after: int
    count: int = 0

    def on_progress(self, progress) -> None:
        self.count += 1

    def is_set(self) -> bool:
        return self.count >= self.after


def test_a_sweep_stopped_twice_continues_where_it_stopped(tmp_path):
    spec = SweepSpec(ScriptBundle.single("gather.py", SCRIPT), seeds=3, robots=(3,),
                     config=VerificationConfig(duration=0.5))
    with pytest.raises(SweepIncomplete) as gone:
        run_sweep(spec, tmp_path, ClusterGone(after=1))
    text = str(gone.value)
    assert "2 of 3 runs" in text and "the cluster at 10.0.0.7:6379 is gone" in text
    assert "Not done: robots=3 seed=1, robots=3 seed=2" in text and "run the same command again" in text
    assert [r.seed for r in gone.value.missing] == [1, 2]
    partial = list(csv.DictReader((tmp_path / "results.csv").open()))
    assert [r["seed"] for r in partial] == ["0"]  # what finished is readable at once
    assert "INCOMPLETE: 1 of 3 runs finished" in (tmp_path / "report.html").read_text()

    stop = CancelAfter(after=1)
    with pytest.raises(SweepIncomplete, match="it was cancelled") as cancelled:
        run_sweep(spec, tmp_path, SerialExecutor(), on_progress=stop.on_progress, cancel=stop)
    assert [r.seed for r in cancelled.value.missing] == [2]

    done = run_sweep(spec, tmp_path, SerialExecutor())
    assert (done.ran, done.cached) == (1, 2)
    rows = list(csv.DictReader((tmp_path / "results.csv").open()))
    assert [(r["seed"], r["status"]) for r in rows] == [("0", "ok"), ("1", "ok"), ("2", "ok")]
    assert rows[0] == partial[0]  # the first run's row, kept as it was
    again = run_sweep(spec, tmp_path, SerialExecutor())
    assert (again.ran, again.cached) == (0, 3)
    assert (tmp_path / "runs").is_dir() and len(list((tmp_path / "runs").glob("*.json"))) == 3


def test_a_run_the_machine_failed_is_a_row_but_is_tried_again(tmp_path):
    slow = b"import time\ntime.sleep(30)\n" + SCRIPT  # never builds its Arena within the run's 0.5 s of wall time
    spec = SweepSpec(ScriptBundle.single("gather.py", slow), robots=(3,),
                     config=VerificationConfig(duration=0.5, wall_factor=1.0001, boot_s=1e-3))
    first = run_sweep(spec, tmp_path, SerialExecutor())
    assert (first.rows[0]["status"], first.rows[0]["ended_by"]) == ("failed", "wall")
    assert not list((tmp_path / "runs").glob("*.json"))  # not cached: the wall budget may be the machine's fault
    assert run_sweep(spec, tmp_path, SerialExecutor()).ran == 1  # the next invocation runs it again
