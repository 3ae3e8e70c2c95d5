"""Coverage behind on worker threads (console/runtime/coverage_worker.py): tick k's coverage is exactly
the coverage of tick k − depth's inputs (bit for bit; depth 2 in the console, 1 on request), two runs give
the same bits, a late worker stops the robots for the tick and is counted, an error in a worker is the
next tick's, and "auto" keeps the synchronous path below 2000 robots."""
from __future__ import annotations

import threading

import numpy as np
import pytest

from swarmdeck.console.runtime.behaviours import Coverage, TickInput
from swarmdeck.console.runtime.coverage_worker import AUTO_MIN_ROBOTS, PipelinedCoverage, use_worker
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.console.runtime.params import BehaviourParams
from swarmdeck.coverage import CoverageConfig, coverage_tick

N, TICKS = 24, 7


def _run(worker: str, depth: int | None = None) -> list:
    loop = ControlLoop(LoopConfig(n_robots=N, seed=5, coverage_worker=worker))
    if depth is not None:
        loop.use_behaviour(PipelinedCoverage(BehaviourParams(), LoopConfig().bounds, LoopConfig().max_speed, 0.17,
                                             depth=depth))
    try:
        return [loop.tick() for _ in range(TICKS)]
    finally:
        loop.close()


@pytest.fixture(scope="module")
def piped() -> list:
    return _run("on")


def _check_behind(frames: list, depth: int) -> None:
    config = CoverageConfig(max_speed=LoopConfig().max_speed, bounds=LoopConfig().bounds)
    for k in range(depth, TICKS):
        before, frame = frames[k - depth], frames[k]
        _, state, _ = coverage_tick(before.points, before.density, config, before.run_time)
        assert state.ok and frame.coverage is not None
        assert np.array_equal(frame.coverage.centroids, state.centroids), k
        assert np.array_equal(frame.coverage.cell_vertices, state.cells.vertices), k
    # the first tick's coverage is computed at once and used for the first depth + 1 ticks
    for k in range(1, depth + 1):
        assert np.array_equal(frames[0].coverage.centroids, frames[k].coverage.centroids)
    assert not np.array_equal(frames[depth].coverage.centroids, frames[depth + 1].coverage.centroids)
    assert any(np.any(f.nominal != 0.0) for f in frames)


def test_the_console_runs_the_coverage_of_tick_k_minus_2_bit_for_bit(piped: list) -> None:
    _check_behind(piped, 2)


def test_one_worker_runs_the_coverage_of_tick_k_minus_1_bit_for_bit() -> None:
    _check_behind(_run("off", depth=1), 1)


def test_two_pipelined_runs_give_the_same_bits(piped: list) -> None:
    again = _run("on")
    for a, b in zip(piped, again):
        for name in ("poses", "nominal", "safe", "v", "w"):
            assert np.array_equal(getattr(a, name), getattr(b, name)), name
        assert np.array_equal(a.coverage.centroids, b.coverage.centroids)


def test_auto_keeps_the_synchronous_path_below_the_threshold() -> None:
    assert not use_worker("auto", AUTO_MIN_ROBOTS - 1) and use_worker("auto", AUTO_MIN_ROBOTS)
    assert use_worker("on", 1) and not use_worker("off", 10**6)
    with pytest.raises(ValueError, match="coverage_worker"):
        use_worker("sometimes", 10)
    with pytest.raises(ValueError, match="coverage_worker"):
        LoopConfig(coverage_worker="sometimes")
    loop = ControlLoop(LoopConfig(n_robots=12, seed=1))
    try:
        assert type(loop._behaviour) is Coverage
    finally:
        loop.close()


def test_a_late_worker_stops_the_robots_for_the_tick_and_is_counted() -> None:
    loop = ControlLoop(LoopConfig(n_robots=N, seed=5, coverage_worker="on"))
    gate = threading.Event()
    behaviour = loop._behaviour
    assert isinstance(behaviour, PipelinedCoverage)
    behaviour.timeout = 0.05
    try:
        loop.tick()                                   # tick 0: computed at once, used for ticks 0, 1, 2
        ctrl = behaviour._ctrl
        diagram = ctrl.diagram

        def held(*args: object) -> object:
            assert gate.wait(60), "the test never opened the gate"
            return diagram(*args)

        ctrl.diagram = held
        loop.tick()                                   # tick 1: tick 0's answer; tick 1's diagram waits at the gate
        loop.tick()                                   # tick 2: tick 0's answer again
        late = loop.tick()                            # tick 3: tick 1's answer is held: robots stopped, counted
        assert behaviour.late == 1 and loop.errors.get("behaviour", 0) == 1
        assert np.all(late.v == 0.0) and np.all(late.w == 0.0)
        gate.set()
        behaviour.timeout = 60.0
        ok = loop.tick()                              # tick 4: tick 1's answer (waited for again), robots move
        assert loop.errors.get("behaviour", 0) == 1 and np.any(ok.v != 0.0)
        assert "ticks late" in ok.health.get("coverage", "")
    finally:
        gate.set()
        loop.close()


def test_an_error_in_the_worker_is_reported_on_the_next_tick_and_the_pipeline_restarts() -> None:
    b = PipelinedCoverage(BehaviourParams(), LoopConfig().bounds, 0.2, 0.17)
    loop = ControlLoop(LoopConfig(n_robots=N, seed=5))
    density = loop.density
    rng = np.random.default_rng(2)
    pts = rng.uniform([-1.4, -0.8], [1.4, 0.8], (N, 2))

    def tick(points: np.ndarray) -> TickInput:
        poses = np.column_stack([points, np.zeros(len(points))])
        return TickInput(poses, points, 0.0, density, LoopConfig().bounds, 0.2, np.arange(len(points)))

    try:
        b(tick(pts))
        bad = pts.copy()
        bad[0] = np.nan
        b(tick(bad))                                  # the workers get non-finite points ...
        b(tick(pts))
        with pytest.raises(ValueError, match="NaN"):
            b(tick(pts))                              # ... and its error is the next tick's
        u, state = b(tick(pts))                       # afresh: this tick's coverage, at once
        assert state.ok and u.shape == (N, 2)
        b.close()                                     # replaced while the loop still held it: computed at once
        u, state = b(tick(pts))
        assert state.ok and u.shape == (N, 2)
    finally:
        b.close()
        loop.close()


def test_a_recording_from_before_the_setting_resimulates_synchronously() -> None:
    from swarmdeck.console.recording.resimulate import _with_worker_setting, loop_config_from_dict, loop_config_to_dict

    old = loop_config_to_dict(LoopConfig(n_robots=5000))
    del old["coverage_worker"]
    assert loop_config_from_dict(_with_worker_setting(old)).coverage_worker == "off"
    kept = loop_config_to_dict(LoopConfig(n_robots=5000, coverage_worker="on"))
    assert loop_config_from_dict(_with_worker_setting(kept)).coverage_worker == "on"
