"""A region stopped by an emergency stop leaves the floor's lockstep: its job may never send again (the portal keeps
its robots where they stopped until an operator releases it) and the other regions' robots keep moving — the floor
ticks on their commands alone, the stopped region's robots zero and fixed."""
from __future__ import annotations

import threading

import numpy as np

from swarmdeck.core.ports import rows_of
from swarmdeck.devices.fleet.floor import simulated_floor
from swarmdeck.devices.fleet.regions import RegionLayout

TICKS = 30


def test_the_other_region_runs_on_while_a_stopped_region_sends_nothing():
    floor = simulated_floor(RegionLayout.grid(columns=2), 2)
    west, east = floor.open_region("r0c0", 2), floor.open_region("r0c1", 2)
    before = floor.reading()
    floor.estop("r0c0")  # west's job never sends again
    done = threading.Event()

    def drive_east() -> None:
        for _ in range(TICKS):
            east.send(np.arange(2), np.full(2, -0.1), np.zeros(2))  # parked facing the wall: back away
        done.set()

    worker = threading.Thread(target=drive_east, daemon=True)
    worker.start()
    worker.join(60.0)
    floor.close()  # ends a wait that would otherwise never end (the defect), so the thread always ends
    assert done.is_set(), "the east region's ticks waited for the stopped west region (lockstep not left)"
    after = floor.reading()
    assert floor.stats.ticks == TICKS
    rows_w = rows_of(before.ids, west.fleet_ids)[0]
    rows_e = rows_of(before.ids, east.fleet_ids)[0]
    np.testing.assert_array_equal(np.asarray(after.poses)[rows_w], np.asarray(before.poses)[rows_w])
    assert np.all(np.linalg.norm(np.asarray(after.poses)[rows_e, :2] - np.asarray(before.poses)[rows_e, :2],
                                 axis=1) > 0.03)
