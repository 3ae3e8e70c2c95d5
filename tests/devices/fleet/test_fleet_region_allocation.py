"""Regions allocated per job (``RegionLayout.guillotine``, ``regions=auto:COLSxROWS``): the floor as a tree of
guillotine cuts down to a grid of leaves. Every region lies inside the floor, any two are disjoint or one lies
inside the other, the leaves tile the floor, and a region is free only when none nested with it runs a job (``fit``,
``conflicts``, and the floor refuses to open two nested regions at once)."""
from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmdeck.core.bounds import Bounds
from swarmdeck.devices.fleet.floor import simulated_floor
from swarmdeck.devices.fleet.regions import RegionLayout, _inside, _overlap


@settings(max_examples=15, deadline=None)
@given(columns=st.integers(1, 5), rows=st.integers(1, 3))
def test_the_guillotine_tree_nests_and_tiles(columns, rows):
    floor = Bounds(-1.6, 1.6, -1.0, 1.0)
    layout = RegionLayout.guillotine(floor, columns, rows)
    regions = {r.name: r for r in layout.regions}
    assert len(regions) == 2 * columns * rows - 1  # a binary tree over columns × rows leaves
    assert set(layout.leaves) == ({f"r{r}c{c}" for r in range(rows) for c in range(columns)} if columns * rows > 1
                                  else {"all"})
    assert layout.regions[-1].name == "all" and layout.regions[-1].bounds == floor
    area = sum(regions[n].bounds.width * regions[n].bounds.height for n in layout.leaves)
    assert area == pytest.approx(floor.width * floor.height)
    for a, b in itertools.combinations(layout.regions, 2):
        if _overlap(a.bounds, b.bounds):
            assert _inside(a.bounds, b.bounds) or _inside(b.bounds, a.bounds), (a.name, b.name)
            assert b.name in layout.conflicts(a.name) and a.name in layout.conflicts(b.name)
        else:
            assert b.name not in layout.conflicts(a.name)
    areas = [round(r.bounds.width * r.bounds.height, 9) for r in layout.regions]
    assert areas == sorted(areas)  # smallest first: the plan's tie-break


def test_a_job_gets_the_smallest_free_region_that_holds_it_and_nested_regions_exclude_each_other():
    layout = RegionLayout.guillotine(columns=4, rows=2)
    cap = layout.capacity()
    assert layout.fit(4).name in layout.leaves
    assert cap[layout.fit(6).name] == 12 and layout.fit(6).name == "r0-0c0-1"  # more than a leaf: a quarter
    assert layout.fit(30).name == "all" and layout.never_fits(51) is not None
    assert layout.fit(4, busy={"all"}) is None  # the whole floor runs a job: nothing else fits
    assert layout.fit(13, busy={"r0c0"}).name == "r0-1c2-3"  # the half around r0c0 is taken
    floor = simulated_floor(layout, {n: 6 for n in layout.leaves})
    assert len(floor.reading().ids) == 6 * 8  # robots parked in the leaves only
    floor.open_region("r0c0", 2)
    with pytest.raises(ValueError, match="overlaps region r0c0, which runs a job"):
        floor.open_region("r0-1c0-1", 2)
    wide = floor.open_region("r0-1c2-3", 20)  # a nested region beside it holds robots of several leaves
    assert len(np.unique(wide.fleet_ids)) == 20
    floor.close()
