"""A region whose job stops sending commands (its script sleeps, blocks, or answers just inside its own per-tick
backstop) must not hold the floor's other regions up to its wall-time limit: after the floor's bounded wait
(``stall_s``) it is stopped as stalled — its robots zero and fixed, counted in ``stats.stalled``, its job told through
``on_stall`` — and the other regions go on. Asserts the outcome only (which region, what was said), never a time."""
from __future__ import annotations

import threading

import numpy as np
import pytest

from swarmdeck.core.ports import rows_of
from swarmdeck.devices.fleet.floor import simulated_floor
from swarmdeck.devices.fleet.regions import RegionLayout

TICKS = 20


def test_a_stalled_region_is_stopped_and_told_and_the_other_region_goes_on():
    told: list[tuple[str, str]] = []
    floor = simulated_floor(RegionLayout.grid(columns=2), 2)
    floor.stall_s, floor.on_stall = 0.2, lambda name, why: told.append((name, why))
    west, east = floor.open_region("r0c0", 2), floor.open_region("r0c1", 2)
    west.watched = True  # its job's script drives it (after the set-up): a stall stops it
    before = floor.reading()
    done = threading.Event()

    def drive_east() -> None:
        for _ in range(TICKS):
            east.send(np.arange(2), np.full(2, -0.1), np.zeros(2))
        done.set()

    worker = threading.Thread(target=drive_east, daemon=True)
    worker.start()
    worker.join(60.0)
    floor.close()  # ends a wait that would otherwise never end (the defect), so the thread always ends
    assert done.is_set(), "the east region waited for the stalled west region without bound"
    assert floor.stats.stalled == ["r0c0"] and "r0c0" in floor.stats.stopped
    assert [name for name, _ in told] == ["r0c0"]
    assert "region r0c0 stalled" in told[0][1] and "no commands for 0.2 s" in told[0][1]
    after = floor.reading()
    rows_w = rows_of(before.ids, west.fleet_ids)[0]
    np.testing.assert_array_equal(np.asarray(after.poses)[rows_w], np.asarray(before.poses)[rows_w])
    assert floor.stats.ticks == TICKS
    assert floor.stats.to_dict()["stalled"] == ["r0c0"]


def test_the_stall_limit_is_off_in_process_and_must_be_a_positive_time():
    layout = RegionLayout.grid(columns=2)
    ports = simulated_floor(layout, 1).ports
    from swarmdeck.devices.fleet.floor import SharedFloor

    assert SharedFloor(ports, layout).stall_s is None  # trusted in-process jobs wait as long as it takes
    for bad in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="stall_s must be a positive number of seconds"):
            SharedFloor(ports, layout, stall_s=bad)


def test_a_region_in_its_set_up_or_return_is_not_judged_a_stall():
    """Set-ups and returns are the runner's own code (a thread starved on a loaded machine is no hostile script):
    only a region whose script drives its robots is stopped as stalled."""
    floor = simulated_floor(RegionLayout.grid(columns=2), 2)
    floor.stall_s = 0.05
    west, east = floor.open_region("r0c0", 2), floor.open_region("r0c1", 2)  # west: not watched (its set-up)
    done = threading.Event()

    def drive_east() -> None:
        try:
            east.send(np.arange(2), np.zeros(2), np.zeros(2))
        except Exception:  # noqa: BLE001 - the floor closed under it: the thread ends
            pass
        done.set()

    worker = threading.Thread(target=drive_east, daemon=True)
    worker.start()
    worker.join(0.5)  # east waits; a wrong stall would stop west and tick
    stalled = list(floor.stats.stalled)
    west.send(np.arange(2), np.zeros(2), np.zeros(2))  # west's set-up sends: the tick comes
    worker.join(60.0)
    floor.close()
    assert done.is_set(), "east never got its tick"
    assert stalled == [] and floor.stats.stalled == [] and floor.stats.ticks == 1
