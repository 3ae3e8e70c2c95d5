"""Region layouts of one floor: bad layouts are refused naming the regions; capacity, fit, the [regions] table."""
from __future__ import annotations

import numpy as np
import pytest

from swarmdeck.core.bounds import DEFAULT_BOUNDS, Bounds
from swarmdeck.devices.chargers import ChargerLayout
from swarmdeck.devices.fleet.regions import MIN_REGION_SIDE, Region, RegionLayout


def test_two_halves_hold_half_the_fleet_each_and_fit_picks_the_smallest_free():
    layout = RegionLayout.from_mapping({"west": {"bounds": [-1.6, 0.4, -1.0, 1.0], "chargers": ["left", "bottom"]},
                                        "east": {"bounds": [0.4, 1.6, -1.0, 1.0], "chargers": ["right", "bottom"]}})
    cap = layout.capacity()
    assert cap["west"] > cap["east"] > 6
    assert layout.fit(6).name == "east"  # the smallest that holds it
    assert layout.fit(6, busy={"east"}).name == "west"
    assert layout.fit(6, busy={"east", "west"}) is None
    assert layout.fit(cap["west"] + 1) is None
    assert "largest region" in layout.never_fits(cap["west"] + 1)
    assert layout.never_fits(6) is None
    west = layout.region("west")
    assert west.origin == pytest.approx((-0.6, 0.0))
    assert np.allclose(west.local_bounds, [-1.0, 1.0, -1.0, 1.0])
    p = np.array([[-1.0, 0.5, 1.0]])
    assert np.allclose(west.to_floor(west.to_local(p)), p)
    assert np.allclose(west.to_local(p), [[-0.4, 0.5, 1.0]])


def test_robot_bounds_give_each_robot_its_region():
    layout = RegionLayout.grid(DEFAULT_BOUNDS, columns=2)
    positions = np.array([[-1.0, 0.0], [1.0, 0.0], [-0.5, 0.2]])
    b = layout.robot_bounds(positions, {"r0c1": [2]})  # robot 2 stands in the west but runs in the east
    assert np.allclose(b[0], [-1.6, 0.0, -1.0, 1.0])
    assert np.allclose(b[1], [0.0, 1.6, -1.0, 1.0])
    assert np.allclose(b[2], [0.0, 1.6, -1.0, 1.0])


@pytest.mark.parametrize(("regions", "words"), [
    ({"a": {"bounds": [-1.6, 0.1, -1, 1]}, "b": {"bounds": [0.0, 1.6, -1, 1]}}, ["a and b overlap"]),
    ({"a": {"bounds": [-1.6, -1.4, -1, 1]}}, ["region a", "smaller than one robot's footprint"]),
    ({"a": {"bounds": [-1.7, 0.0, -1, 1]}}, ["region a", "leaves the floor"]),
    ({"a": {"bounds": [-1.6, 0.0, -1, 1], "chargers": ["left"]},
      "b": {"bounds": [0.0, 1.6, -1, 1], "chargers": ["bottom"]},
      "c": {"bounds": [-1.6, 1.6, 1.5, 2.0]}}, ["region c", "leaves the floor"]),
    ({"a": {"bounds": [-1.6, 0.0, -1, 1], "chargers": ["right"]}}, ["region a", "does not reach", "right"]),
    ({"a": {"bounds": [-1.6, 0.0, -1, 1], "chargers": ["bottom"]},
      "b": {"bounds": [0.0, 1.6, -1, 1], "chargers": ["right"]},
      "c": {"bounds": [-1.6, 1.6, -1, -0.6]}}, ["overlap"]),
    ({"a": {"bounds": [-1.6, 0.0, -1, 1], "chargers": ["bottom"]},
      "b": {"bounds": [0.0, 1.6, -1, 1]}}, ["region b covers part of the bottom charger strip", "region a docks on"]),
    ({"a": {"bounds": [-1.6, -1.2, -1, 1], "chargers": ["left"]}}, ["region a", "approach area"]),
    ({"a": {"bounds": [-1.6, 0.0, -1, 1], "colour": "red"}}, ["[regions.a]", "unknown key", "colour"]),
    ({"a": {"chargers": ["left"]}}, ["[regions.a]", "bounds", "missing"]),
    ({"a": {"bounds": [0, 1]}}, ["[regions.a] bounds"]),
    ({"a": {"bounds": [-1.6, 0, -1, 1], "chargers": "left"}}, ["[regions.a]", "chargers must be a list"]),
    ({"a b": {"bounds": [-1.6, 0, -1, 1]}}, ["region name 'a b'"]),
    ({"a": {"bounds": [-1.6, 0, -1, 1], "chargers": ["north"]}}, ["region a", "chargers must be distinct walls"]),
    ({}, ["[regions] must be a table"]),
])
def test_bad_layouts_are_refused_naming_what_is_wrong(regions, words):
    with pytest.raises(ValueError) as err:
        RegionLayout.from_mapping(regions)
    for w in words:
        assert w in str(err.value), (w, str(err.value))


def test_a_region_too_narrow_for_a_slot_of_its_strip_is_refused():
    with pytest.raises(ValueError, match="region x: has no slot of the bottom charger strip"):
        RegionLayout(DEFAULT_BOUNDS, (Region("x", Bounds(0.19, 0.48, -1.0, 1.0), ("bottom",)),))
    assert MIN_REGION_SIDE == pytest.approx(0.28)


def test_a_floor_without_strips_on_a_wall_leaves_its_regions_free_of_them():
    chargers = ChargerLayout(DEFAULT_BOUNDS, walls=("left", "right"))
    layout = RegionLayout.grid(DEFAULT_BOUNDS, columns=3, charger_layout=chargers)
    assert [r.chargers for r in layout.regions] == [("left",), (), ("right",)]
    assert layout.capacity()["r0c1"] > 0  # no strip: space alone
    assert layout.to_dict()["regions"][0]["name"] == "r0c0"
