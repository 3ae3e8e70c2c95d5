"""Two and three experiments at once on one simulated floor: each script unmodified, each result shaped as a solo
run's, no robot ever outside its region, no contact anywhere (a hypothesis property over layouts and scripts)."""
from __future__ import annotations

import threading
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from swarmdeck.console.runtime.region_jobs import run_in_region
from swarmdeck.core.bounds import DEFAULT_BOUNDS
from swarmdeck.core.constants import ROBOT_DIAMETER
from swarmdeck.devices.chargers import ChargerLayout
from swarmdeck.devices.fleet.floor import simulated_floor
from swarmdeck.devices.fleet.regions import RegionLayout
from swarmdeck.devices.runner import run_experiment

# Scripts as a researcher writes them for a solo arena; none knows about regions.
SCRIPTS = {
    # full speed at the right wall with its own barrier off: only the floor's barrier holds it
    "rammer.py": """
import numpy as np
from swarmdeck.devices import Arena

arena = Arena(safety=False)
while True:
    arena.step_unicycle(np.full(arena.n, 0.2), np.zeros(arena.n))
""",
    # goals anywhere in what it believes is its arena, up to its walls
    "goals.py": """
import numpy as np

def experiment(arena):
    x0, x1, y0, y1 = arena.config.bounds
    goals = np.random.default_rng(arena.n).uniform([x0, y0], [x1, y1], (arena.n, 2))
    inside = True
    while arena.time < arena.duration - 1e-9:
        p = arena.positions()
        inside &= bool(np.all((p[:, 0] >= x0) & (p[:, 0] <= x1) & (p[:, 1] >= y0) & (p[:, 1] <= y1)))
        arena.set_goals(goals)
        arena.step()
    return {"bounds": [x0, x1, y0, y1], "ids": arena.ids.tolist(), "inside": inside,
            "poses": arena.poses().shape}
""",
    # spinning circles at the wheels' limit
    "circles.py": """
import numpy as np
from swarmdeck.devices import Arena

arena = Arena()
while True:
    arena.set_wheel_speeds(np.full(arena.n, 12.5), np.full(arena.n, 6.0))
    arena.step()
""",
}


def _layout(cuts: list[float]) -> RegionLayout:
    xs = [DEFAULT_BOUNDS.x_min, *cuts, DEFAULT_BOUNDS.x_max]
    chargers = ChargerLayout(DEFAULT_BOUNDS, walls=("bottom", "top"))
    return RegionLayout.from_mapping(
        {f"r{k}": {"bounds": [xs[k], xs[k + 1], -1.0, 1.0], "chargers": ["bottom", "top"]} for k in range(len(xs) - 1)},
        DEFAULT_BOUNDS, chargers)


@st.composite
def floors(draw: st.DrawFn) -> tuple[list[float], list[str], int]:
    k = draw(st.sampled_from([2, 3]))
    width = 3.2 / k
    cuts = [DEFAULT_BOUNDS.x_min + width * (i + 1) + draw(st.floats(-0.15, 0.15)) for i in range(k - 1)]
    scripts = [draw(st.sampled_from(sorted(SCRIPTS))) for _ in range(k)]
    return cuts, scripts, draw(st.integers(2, 4))


def _write(tmp: Path) -> dict[str, Path]:
    out = {}
    for name, text in SCRIPTS.items():
        out[name] = tmp / name
        out[name].write_text(text)
    return out


@settings(max_examples=3, suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(floors())
def test_concurrent_jobs_stay_in_their_regions_and_never_touch(tmp_path, case):
    cuts, scripts, n = case
    paths = _write(tmp_path)
    layout = _layout(cuts)
    floor = simulated_floor(layout, n)
    results = {}

    def job(region: str, script: str) -> None:
        # the jobs start where their robots stand: this property is about safety and results (set-ups to given
        # poses are exercised by test_fleet_region_wall_held.py and the portal's test)
        results[region] = run_in_region(floor, region, paths[script], n_robots=n, duration=2.0, seed=7,
                                        start_poses="parked")

    threads = [threading.Thread(target=job, args=(r.name, s)) for r, s in zip(layout.regions, scripts)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(600)
    assert not any(t.is_alive() for t in threads)

    assert floor.stats.outside == 0 and floor.stats.barrier_failures == 0
    assert floor.stats.min_between_regions >= ROBOT_DIAMETER
    report = floor.ports.report
    assert report.collision_pairs == 0 and report.steps_with_collision == 0
    for region, script in zip(layout.regions, scripts):
        got = results[region.name]
        assert got.error is None and got.setup["ok"] and got.returned["ok"], (got.error, got.setup, got.returned)
        solo = run_experiment(paths[script], n_robots=n, duration=2.0, seed=7, bounds=region.local_bounds)
        assert got.run.error == solo.error is None
        assert [r.n_robots for r in got.run.reports] == [r.n_robots for r in solo.reports] == [n]
        assert abs(got.run.reports[0].time - solo.reports[0].time) < 0.05
        if script == "goals.py":  # what the script saw: its region as its arena, robots 0..n-1
            assert got.run.returned["bounds"] == list(region.local_bounds) == solo.returned["bounds"]
            assert got.run.returned["ids"] == list(range(n)) == solo.returned["ids"]
            assert got.run.returned["inside"] and got.run.returned["poses"] == solo.returned["poses"]
