"""Verification runs a job in the region it will get: the script's arena is the region (its bounds as the script
sees them), the random start poses lie in it and the region's walls are the runs' walls."""
import numpy as np
import pytest

from swarmdeck.console.sandbox.executors import SerialExecutor
from swarmdeck.console.sandbox.verification import VerificationConfig, verify
from swarmdeck.devices.fleet.regions import RegionLayout

SEES = """
import numpy as np
from swarmdeck.devices import Arena

arena = Arena()
print("BOUNDS", [round(v, 4) for v in arena.config.bounds])
while True:  # full speed at the region's wall
    arena.step_unicycle(np.full(arena.n, 0.2), np.zeros(arena.n))
"""


def test_verification_runs_the_job_in_its_region(tmp_path):
    region = RegionLayout.grid(columns=3).region("r0c1")  # 1.07 m x 2 m in the middle of the floor
    script = tmp_path / "sees.py"
    script.write_text(SEES)
    config = VerificationConfig(n_robots=3, duration=1.0, runs=1, bounds=region.local_bounds)
    report = verify([script], config, SerialExecutor()).to_dict()
    assert report["config"]["bounds"] == pytest.approx(list(region.local_bounds))
    runs = report["scripts"][0]["runs"]
    assert {r["mode"] for r in runs} == {"raw", "wrapped"}
    for run in runs:
        assert run["error"] is None and f"BOUNDS {[round(v, 4) for v in region.local_bounds]}" in run["log"]
        assert region.local_bounds.contains(np.array(run["start_poses"])).all()
    wrapped = next(r for r in runs if r["mode"] == "wrapped")
    assert wrapped["validation"]["steps_with_boundary"] == 0  # the barrier holds the region's walls


def test_start_poses_outside_the_region_are_refused():
    region = RegionLayout.grid(columns=3).region("r0c1")
    with pytest.raises(ValueError, match=r"initial_poses: pose 0 \(1.000, 0.000, 0.000\) is outside the arena"):
        VerificationConfig(n_robots=1, initial_poses=((1.0, 0.0, 0.0),), bounds=region.local_bounds)
