"""Same seeds, same table: a sweep run serially, on a local pool of 2 and on Ray (a local cluster) writes the same
results.csv byte for byte, and the same Parquet table; a run whose script crashes is a failed row with its error
and the sweep goes on; the script's metrics and the built-in ones are columns."""
import csv

import pytest

from swarmdeck.console.sandbox.bundle import ScriptBundle
from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.executors import LocalPoolExecutor, RayExecutor, SerialExecutor
from swarmdeck.console.sandbox.verification import VerificationConfig
from swarmdeck.console.sweep.campaign import SweepSpec, run_sweep
from swarmdeck.console.sweep.design import parse_axis

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")

SCRIPT = b"""
from swarmdeck.devices import params, record_metrics
p = params(gain=1.0)

def experiment(arena):
    if p.gain > 2:
        raise RuntimeError(f"gain {p.gain} is too high for this controller")
    while True:
        x = arena.positions()
        arena.set_velocities(-p.gain * (x - x.mean(axis=0)))
        record_metrics(spread=float(x.std()), gain_seen=p.gain)
        arena.step()
"""


def spec() -> SweepSpec:
    return SweepSpec(ScriptBundle.single("gather.py", SCRIPT), (parse_axis("gain=0.5,3"),), seeds=2, robots=(4,),
                     config=VerificationConfig(duration=1.0))


@pytest.fixture(scope="module")
def serial(tmp_path_factory):
    out = tmp_path_factory.mktemp("serial")
    return out, run_sweep(spec(), out, SerialExecutor())


def test_a_crashing_point_is_a_failed_row_and_the_sweep_goes_on(serial):
    out, result = serial
    rows = list(csv.DictReader((out / "results.csv").open()))
    assert [(r["gain"], r["seed"], r["status"]) for r in rows] == [
        ("0.5", "0", "ok"), ("0.5", "1", "ok"), ("3.0", "0", "failed"), ("3.0", "1", "failed")]
    assert "gain 3.0 is too high for this controller" in rows[2]["error"] and "gather.py" in rows[2]["error"]
    ok = rows[0]
    assert ok["metric_gain_seen"] == "0.5" and float(ok["metric_spread"]) > 0  # the script got its point's value
    assert ok["contacts"] != "" and float(ok["min_distance"]) > 0 and ok["barrier_interventions"] != ""
    assert float(ok["coverage_cost_H"]) > 0 and ok["robots"] == "4" and ok["ended_by"] == "duration"
    assert result.ran == 4 and result.cached == 0 and result.failed == 2
    summary = list(csv.DictReader((out / "summary.csv").open()))
    assert summary[0]["runs"] == "2" and summary[0]["failed"] == "0" and summary[1]["failed"] == "2"
    assert summary[0]["metric_spread_ci_low"] != ""  # two seeds: an interval
    assert (out / "report.html").read_text().count("gain 3.0 is too high") == 1  # one error, named once with its runs
    assert (out / "results.parquet").exists()


@pytest.mark.slow
def test_the_local_pool_and_ray_write_the_same_table(serial, tmp_path):
    import pyarrow.parquet as pq

    ray = pytest.importorskip("ray")
    out, _ = serial
    expected = (out / "results.csv").read_bytes()
    pool = tmp_path / "pool"
    run_sweep(spec(), pool, LocalPoolExecutor(2))
    assert (pool / "results.csv").read_bytes() == expected
    assert pq.read_table(pool / "results.parquet").equals(pq.read_table(out / "results.parquet"))
    on_ray = tmp_path / "ray"
    try:
        run_sweep(spec(), on_ray, RayExecutor("local", num_cpus=2))
    finally:
        ray.shutdown()
    assert (on_ray / "results.csv").read_bytes() == expected
    assert (on_ray / "summary.csv").read_bytes() == (out / "summary.csv").read_bytes()
