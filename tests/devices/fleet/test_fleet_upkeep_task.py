"""One fleet-upkeep task, two drivers: ``FleetManager`` (``drive`` over the fleet's ports) and the console
loop (the ``FleetManeuver`` behaviour) apply the same rules to the same scene — the same robots reach the same
poses, or fail on the time limit naming the same robots — and ``drive`` now stops on a lost robot as the console does."""
from __future__ import annotations

import numpy as np
import pytest

from swarmdeck.console.runtime import fleet_upkeep as fu
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.core.ports import SensedPoses
from swarmdeck.devices import ArenaConfig
from swarmdeck.devices.fleet import ChargerLayout, FleetManager, Maneuver, SetupFailed, UpkeepTask, drive
from swarmdeck.devices.pipeline import barrier_filter
from swarmdeck.devices.simulated_robots import SimulatedRobots

CHARGERS = ChargerLayout()
GOALS = np.array([[-1.0, -0.4, 0.0], [-0.6, -0.3, 1.2], [-0.2, -0.5, -2.0]])


def _through_fleet(time_limit: float | None) -> tuple[FleetManager, list[int], str]:
    fleet = FleetManager(6, slots=np.arange(6))
    try:
        report = fleet.setup(GOALS, time_limit=time_limit)
    except SetupFailed as exc:
        return fleet, exc.report.not_at_pose, str(exc)
    assert report.ok and report.collision_steps == 0
    return fleet, [], "done"


def _through_loop(time_limit: float | None) -> tuple[ControlLoop, fu.FleetManeuver, fu.UpkeepResult]:
    sim = SimulatedRobots(6, ArenaConfig(), chargers=CHARGERS, start_docked=True)
    loop = ControlLoop(LoopConfig(n_robots=6), source=sim, sink=sim)
    loop.pause()
    frame = loop.tick()
    m = fu.set_up(fu.FleetView.of(frame), GOALS, frame.bounds, CHARGERS, config=fu.UpkeepConfig(time_limit=time_limit))
    return loop, m, fu.run_maneuver(loop, m)


def test_the_same_setup_through_the_fleet_and_through_the_loop_ends_the_same():
    fleet, _, _ = _through_fleet(None)
    loop, m, result = _through_loop(None)
    loop.close()
    assert isinstance(m.task, UpkeepTask) and m.task.state == "done"
    assert result.ok and result.collisions == 0, result.message
    assigned = fleet.ids[fleet.assignment.rows].tolist()
    assert m.ids.tolist() == assigned  # the same robots play experiment robots 0, 1, 2
    rows = [int(np.flatnonzero(loop.latest.ids == i)[0]) for i in m.ids]
    for poses in (fleet.poses()[fleet.assignment.rows], loop.latest.poses[rows]):
        assert np.all(m.maneuver.at_goal(poses, position=fu.ACCEPT_POSITION, heading=fu.ACCEPT_HEADING))
    assert m.health().startswith("set up: done in ") and "3 robot(s) at their poses" in m.health()


def test_a_setup_out_of_time_names_the_same_robots_in_each_path_s_words():
    _, not_at_pose, fleet_message = _through_fleet(1.0)
    loop, m, result = _through_loop(1.0)
    loop.close()
    assert not result.ok and m.task.state == "failed" and m.task.timed_out
    named = [int(i) for i in m.ids[m.task.not_at_pose]]
    assert sorted(named) == sorted(not_at_pose) and len(named) == 3
    # one task, worded per path as before: the fleet's names headings and says "was stopped"
    assert fleet_message.startswith("setup did not finish within 1 s: robot ") and " deg away" in fleet_message
    assert fleet_message.endswith("; every robot was stopped")
    assert result.message.startswith("set up did not finish within 1 s: robot ") and " deg " not in result.message
    assert result.message.endswith("; every robot stopped")
    for i in named:
        assert f"robot {i} " in fleet_message and f"robot {i} " in result.message


class _LosesRobot(SimulatedRobots):
    """Simulated ports whose robot ``lost`` is unseen from the ``after``-th reading on (a hidden tag)."""

    def __init__(self, poses: np.ndarray, lost: int, after: int) -> None:
        super().__init__(initial_poses=poses, config=ArenaConfig())
        self._lost, self._after, self._reads = lost, after, 0

    def read(self, now: float = 0.0) -> SensedPoses:
        r = super().read(now)
        self._reads += 1
        if self._reads < self._after:
            return r
        seen = r.seen.copy()
        seen[self._lost] = False
        return SensedPoses(r.ids, r.poses, seen, time=r.time)


def test_drive_over_ports_stops_on_a_lost_robot_and_names_it_as_the_console_does():
    start = np.array([[-0.6, 0.0, 0.0], [0.6, 0.0, np.pi], [0.0, 0.6, 0.0]])
    goals = np.array([[-0.6, -0.5, 0.0], [0.6, -0.5, np.pi]])
    robots = _LosesRobot(start, lost=1, after=10)
    filt = barrier_filter(robots.params, ArenaConfig().bounds, 0.033, class_k="linear", gamma=20.0)
    with pytest.raises(SetupFailed, match=r"^setup stopped: robot 1 stopped reporting its pose for more than 0\.5 s; "
                                          r"every robot stopped$") as err:
        drive(robots, Maneuver(goals, ArenaConfig().bounds, robots.params), [0, 1], filt, time_limit=60.0,
              lost_after=0.5)
    report = err.value.report
    assert not report.ok and 0.5 < report.sim_time < 1.0
    assert np.array_equal(robots.sim.applied[0], np.zeros(3))  # the last command stopped every robot
    assert robots.sim.poses[2].tolist() == start[2].tolist()  # the robot that does not take part never moved
