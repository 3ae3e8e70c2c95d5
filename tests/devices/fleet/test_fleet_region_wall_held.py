"""A script driving full speed at its region's wall is held there by the floor's barrier (its own barrier off):
no crossing, no contact with the job on the other side; an emergency stop stops one region or the whole floor."""
from __future__ import annotations

import threading
from pathlib import Path

import numpy as np

from swarmdeck.console.runtime.region_jobs import run_in_region
from swarmdeck.core.constants import ROBOT_DIAMETER, ROBOT_RADIUS
from swarmdeck.devices.fleet.floor import simulated_floor
from swarmdeck.devices.fleet.regions import RegionLayout

RAM = """
import numpy as np
from swarmdeck.devices import Arena

arena = Arena(safety=False)
while True:
    arena.step_unicycle(np.full(arena.n, {v}), np.zeros(arena.n))
"""


def _run(floor, jobs: dict[str, Path], duration: float, started: dict | None = None) -> dict:
    out = {}

    def job(region: str, path: Path) -> None:
        # start poses facing the shared edge at x = 0, 0.25 m from it
        x = -0.55 if region == "r0c0" else 0.55
        th = 0.0 if region == "r0c0" else np.pi
        start = np.array([[x, -0.3, th], [x, 0.0, th], [x, 0.3, th]])
        start[:, 0] -= floor.layout.region(region).origin[0]
        on_start = None if started is None else (lambda view: started[region].set())
        out[region] = run_in_region(floor, region, path, n_robots=3, duration=duration, start_poses=start,
                                    on_start=on_start)

    threads = [threading.Thread(target=job, args=item) for item in jobs.items()]
    for t in threads:
        t.start()
    for t in threads:
        t.join(600)
    assert not any(t.is_alive() for t in threads)
    return out


def _scripts(tmp_path: Path) -> dict[str, Path]:
    paths = {}
    for region, v in (("r0c0", 0.2), ("r0c1", 0.2)):
        paths[region] = tmp_path / f"ram_{region}.py"
        paths[region].write_text(RAM.format(v=v))
    return paths


def test_full_speed_at_the_shared_edge_is_held_with_no_crossing_and_no_contact(tmp_path):
    layout = RegionLayout.grid(columns=2)
    floor = simulated_floor(layout, 3)
    edge: list[float] = []
    floor.on_tick = lambda reading: edge.append(float(np.max(np.abs(reading.poses[:, 0]) <= 0.2)))
    got = _run(floor, _scripts(tmp_path), duration=6.0)
    for r in got.values():
        assert r.error is None and r.run.error is None and r.setup["ok"], (r.error, r.run and r.run.error, r.setup)
    assert floor.stats.outside == 0 and floor.stats.barrier_failures == 0
    assert floor.ports.report.collision_pairs == 0 and floor.ports.report.steps_with_boundary == 0
    assert floor.stats.min_between_regions >= ROBOT_DIAMETER
    assert max(edge) == 1.0  # the rammers reached the edge (within 0.2 m of x = 0), and stayed on their side
    assert min(r.run.reports[0].time for r in got.values()) >= 6.0 - 0.05
    assert ROBOT_RADIUS < 0.2


def test_an_emergency_stop_stops_one_region_and_the_other_runs_on(tmp_path):
    layout = RegionLayout.grid(columns=2)
    floor = simulated_floor(layout, 3)
    seen: dict[str, list[np.ndarray]] = {"r0c0": [], "r0c1": []}
    started = {"r0c0": threading.Event(), "r0c1": threading.Event()}
    ticks = [0]

    def watch(reading) -> None:
        ticks[0] += all(e.is_set() for e in started.values())
        if ticks[0] == 30:  # 1 s into both scripts (20 s each)
            floor.estop("r0c0")
        if floor.stopped("r0c0"):
            seen["r0c0"].append(reading.poses[:3].copy())
            seen["r0c1"].append(reading.poses[3:].copy())

    floor.on_tick = watch
    paths = _scripts(tmp_path)
    paths["r0c0"].write_text(RAM.format(v=-0.1))  # away from the edge: both would keep moving
    paths["r0c1"].write_text(RAM.format(v=-0.1))
    got = _run(floor, paths, duration=20.0, started=started)
    assert floor.stats.stopped == ["r0c0"]
    west, east = np.array(seen["r0c0"]), np.array(seen["r0c1"])
    assert len(west) > 10
    # stopped from the tick after the stop (headings only re-wrapped: 1e-15 rad), and no return (it stays)
    assert np.abs(west[1] - west[-1]).max() < 1e-12
    assert not np.allclose(east[1], east[-1])  # the other region ran on
    assert got["r0c0"].returned == {} and got["r0c1"].returned["ok"]


def test_an_emergency_stop_of_the_floor_stops_every_region(tmp_path):
    layout = RegionLayout.grid(columns=2)
    floor = simulated_floor(layout, 3)
    seen: list[np.ndarray] = []
    started = {"r0c0": threading.Event(), "r0c1": threading.Event()}
    ticks = [0]

    def watch(reading) -> None:
        ticks[0] += all(e.is_set() for e in started.values())
        if ticks[0] == 30:
            floor.estop()
        if floor.stopped("r0c0"):
            seen.append(reading.poses.copy())

    floor.on_tick = watch
    paths = _scripts(tmp_path)
    got = _run(floor, paths, duration=20.0, started=started)
    assert sorted(floor.stats.stopped) == ["r0c0", "r0c1"]
    assert np.abs(seen[1] - seen[-1]).max() < 1e-12
    assert all(r.returned == {} and r.run.error is None for r in got.values())
