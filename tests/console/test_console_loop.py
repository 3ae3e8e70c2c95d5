"""The control loop's Frames on a virtual clock: behaviours, e-stop, pause/step, parameters, safety."""
from __future__ import annotations

import time

import numpy as np
import pytest

from swarmdeck.console.runtime.behaviours import BehaviourError, BehaviourParams
from swarmdeck.console.runtime.loop import ControlLoop, DensityParams, LoopConfig, SafetyParams


def make_loop(**kw) -> ControlLoop:
    kw.setdefault("seed", 7)
    kw.setdefault("n_robots", 8)
    kw.setdefault("script_budget", 0.5)  # scripts here return at once; the budget has its own tests
    return ControlLoop(LoopConfig(**kw))


def test_coverage_frames_are_complete_and_consistent() -> None:
    loop = make_loop()
    frames = [loop.tick() for _ in range(5)]
    f = frames[-1]
    assert [fr.tick for fr in frames] == list(range(5))
    assert f.behaviour == "coverage" and f.run_state == "running" and not f.alerts
    assert f.poses.shape == (8, 3) and f.coverage is not None and f.coverage.centroids.shape == (8, 2)
    assert len(f.coverage.edges) > 0 and f.density is not None and f.barrier.enabled
    assert np.all(np.linalg.norm(f.nominal, axis=1) <= 0.2 + 1e-9)
    # The sent command moves the simulation: the next frame's poses are this one's stepped.
    assert not np.allclose(frames[-2].poses, f.poses)
    assert f.run_time == pytest.approx(4 * 0.033) and f.time == pytest.approx(4 * 0.033)


def test_behaviour_switches_take_effect_next_tick() -> None:
    loop = make_loop()
    loop.tick()
    for name in ("rendezvous", "formation", "goto", "coverage"):
        loop.set_behaviour(name)
        f = loop.tick()
        assert f.behaviour == name
        assert (f.coverage is not None) == (name == "coverage")
        assert f"behaviour: {name}" in f.events
    with pytest.raises(BehaviourError, match="unknown behaviour"):
        loop.set_behaviour("dance")
    assert loop.tick().behaviour == "coverage"


def test_emergency_stop_zeroes_every_command_within_one_tick() -> None:
    loop = make_loop(behaviour="rendezvous")
    for _ in range(10):
        moving = loop.tick()
    assert np.abs(moving.v).max() > 1e-3
    loop.estop()
    stopped = loop.tick()
    assert stopped.run_state == "estop" and stopped.stopped
    assert np.all(stopped.safe == 0.0) and "EMERGENCY STOP" in stopped.events
    after = [loop.tick() for _ in range(3)]
    for a in after:
        np.testing.assert_allclose(a.poses, stopped.poses, atol=1e-12)  # nothing moves any more
    loop.run()  # ignored while engaged
    assert loop.tick().run_state == "estop"
    loop.release()
    assert loop.tick().run_state == "paused"
    loop.run()
    loop.tick()
    assert not np.allclose(loop.tick().poses, stopped.poses)


def test_pause_freezes_simulation_and_step_runs_exactly_one_tick() -> None:
    loop = make_loop(behaviour="rendezvous")
    loop.tick()
    loop.pause()
    p0 = loop.tick()
    p1 = loop.tick()
    np.testing.assert_array_equal(p0.poses, p1.poses)
    assert p1.run_state == "paused" and p1.run_time == p0.run_time and p1.time > p0.time
    assert p1.stopped
    loop.step()
    s = loop.tick()
    assert not s.stopped
    after = loop.tick()
    assert not np.allclose(after.poses, s.poses) and after.run_time == pytest.approx(s.run_time + 0.033)
    np.testing.assert_array_equal(loop.tick().poses, after.poses)


def test_parameter_change_takes_effect() -> None:
    # Lloyd's law u = κ (c − p): doubling κ doubles every (unsaturated) nominal command.
    params = BehaviourParams(law="lloyd", kappa=0.1)
    a = ControlLoop(LoopConfig(seed=3, n_robots=6, behaviour_params=params))
    b = ControlLoop(LoopConfig(seed=3, n_robots=6, behaviour_params=params))
    b.set_params(kappa=0.2)
    fa, fb = a.tick(), b.tick()
    assert fb.params["kappa"] == 0.2 and fa.params["kappa"] == 0.1
    np.testing.assert_allclose(fb.nominal, 2.0 * fa.nominal, rtol=1e-9, atol=1e-12)
    with pytest.raises(ValueError, match="kappa"):
        b.set_params(kappa=50.0)
    assert b.tick().params["kappa"] == 0.2


def test_safety_parameters_and_barrier_off() -> None:
    loop = make_loop(behaviour="rendezvous")
    loop.set_safety(safety_distance=0.25, gamma=50.0)
    f = loop.tick()
    assert f.barrier.safety_distance == 0.25 and f.params["gamma"] == 50.0
    with pytest.raises(ValueError, match="safety_distance"):
        loop.set_safety(safety_distance=2.0)
    loop.set_safety(enabled=False)
    off = loop.tick()
    assert not off.barrier.enabled and "safety barrier OFF" in off.alerts
    # the barrier is never off without the guard (safety.guard): rendezvous heads straight for the others, and
    # the guard switches the barrier back on before any pair comes closer than the guard distance
    frames = [loop.tick() for _ in range(150)]
    assert len(loop.revocations) == 1 and loop.safety_params.enabled and frames[-1].barrier.enabled
    assert sum(e.startswith("BARRIER BACK ON") for f in frames for e in f.events) == 1
    assert min(f.barrier.min_distance for f in frames) >= 0.15 - 1e-9
    # without the guard (a trusted-side hook only: ControlLoop(guard=None)) the nominal goes out unchanged
    bare = ControlLoop(LoopConfig(seed=7, n_robots=8, behaviour="rendezvous"), guard=None)
    bare.set_safety(enabled=False)
    off = bare.tick()
    assert not off.barrier.enabled and "safety barrier OFF" in off.alerts
    np.testing.assert_array_equal(off.safe, off.nominal)


def test_barrier_keeps_rendezvous_apart() -> None:
    loop = make_loop(behaviour="rendezvous", n_robots=10)
    dmin = min(loop.tick().barrier.min_distance for _ in range(250))
    assert dmin >= 0.17 - 2e-3
    f = loop.latest
    assert f.barrier.n_active > 0 and len(f.barrier.active_pairs) == len(f.barrier.active_h)


def _write(tmp_path, body: str):
    p = tmp_path / "beh.py"
    p.write_text(body)
    return p


def test_raising_script_stops_robots_and_loop_survives(tmp_path) -> None:
    path = _write(tmp_path, "import numpy as np\n"
                            "def behaviour(poses, t):\n"
                            "    if t > 0.05:\n"
                            "        raise RuntimeError('boom')\n"
                            "    return np.tile([0.1, 0.0], (len(poses), 1))\n")
    loop = make_loop(behaviour=f"script:{path}")
    ok = loop.tick()
    assert not ok.stopped and not ok.alerts
    for _ in range(3):
        bad = loop.tick()
    assert bad.stopped and any("boom" in a for a in bad.alerts)
    assert any("RuntimeError" in e for f in [bad] for e in f.alerts)
    loop.set_behaviour("coverage")
    good = loop.tick()
    assert not good.alerts and good.behaviour == "coverage"


@pytest.mark.parametrize("body, message", [
    ("def behaviour(poses, t):\n    return [[1.0, 2.0, 3.0]]\n", "shape"),
    ("def behaviour(poses, t):\n    return 'fast please'\n", "ValueError"),
    ("def behaviour(poses, t):\n    return None\n", "shape"),
])
def test_garbage_from_script_stops_robots(tmp_path, body: str, message: str) -> None:
    loop = make_loop(behaviour=f"script:{_write(tmp_path, body)}")
    f = loop.tick()
    assert f.stopped and any(message in a for a in f.alerts)


def test_nan_rows_stop_only_those_robots(tmp_path) -> None:
    body = ("import numpy as np\n"
            "def behaviour(poses, t):\n"
            "    u = np.tile([0.05, 0.0], (len(poses), 1))\n"
            "    u[1] = np.nan\n"
            "    return u\n")
    loop = make_loop(behaviour=f"script:{_write(tmp_path, body)}", n_robots=4)
    f = loop.tick()
    assert np.all(f.nominal[1] == 0.0) and np.abs(f.nominal[[0, 2, 3]]).max() > 0
    assert any("robot(s) [1]" in a for a in f.alerts)


def test_bad_scripts_are_rejected_up_front(tmp_path) -> None:
    with pytest.raises(BehaviourError, match="does not exist"):
        make_loop(behaviour=f"script:{tmp_path / 'missing.py'}")
    no_function = _write(tmp_path, "x = 1\n")
    with pytest.raises(BehaviourError, match="must define"):
        make_loop(behaviour=f"script:{no_function}")
    raising = _write(tmp_path, "raise SystemError(1)\n")
    with pytest.raises(BehaviourError, match="failed to import"):
        make_loop(behaviour=f"script:{raising}")


def test_bumps_enter_the_density_and_draw_robots() -> None:
    loop = ControlLoop(LoopConfig(seed=5, n_robots=6, density=DensityParams(moving=False)))
    f0 = loop.tick()
    assert f0.density.n_bumps == 0
    bid = loop.add_bump((1.0, 0.5), sigma=0.3, weight=3.0)
    for _ in range(20):
        f = loop.tick()
    assert f.density.n_bumps == 1
    np.testing.assert_allclose(f.density.mu[0], (1.0, 0.5))
    assert f.density.weight[0] == pytest.approx(3.0)  # ramp over
    # the cell masses shift towards the bump: the robot nearest to it gains mass
    near = int(np.argmin(np.linalg.norm(f.points - (1.0, 0.5), axis=1)))
    assert f.coverage.masses[near] > f0.coverage.masses[near]
    loop.move_bump(bid, (-1.0, -0.5))
    np.testing.assert_allclose(loop.tick().density.mu[0], (-1.0, -0.5))
    loop.remove_bump(bid)
    for _ in range(20):
        f = loop.tick()
    assert f.density.n_bumps == 0
    with pytest.raises(ValueError, match="outside the arena"):
        loop.add_bump((5.0, 0.0))


def test_threaded_loop_runs_and_stops() -> None:
    loop = make_loop()
    seen = []
    loop.subscribe(lambda fr: seen.append(fr.tick))
    loop.start()
    try:
        deadline = time.monotonic() + 10
        while (loop.latest is None or loop.latest.tick < 5) and time.monotonic() < deadline:
            time.sleep(0.01)
    finally:
        loop.stop()
    n = len(seen)
    assert n >= 6 and seen == list(range(n))
    assert loop.latest.time > 0


def test_failing_listener_does_not_break_the_loop() -> None:
    loop = make_loop()
    loop.subscribe(lambda fr: 1 / 0)
    loop.tick()
    f = loop.tick()
    assert any("ZeroDivisionError" in e for e in f.events) and loop.errors["listener"] == 2


def test_config_validation_names_the_field() -> None:
    with pytest.raises(ValueError, match="n_robots"):
        LoopConfig(n_robots=0)
    with pytest.raises(ValueError, match="gamma"):
        SafetyParams(gamma=0.0)
    with pytest.raises(ValueError, match="law"):
        BehaviourParams(law="magic")


class _FlakySource:
    """A pose source that fails on demand (bad shapes, exceptions)."""

    name = "flaky"

    def __init__(self, inner) -> None:
        self.inner, self.mode = inner, "ok"

    def read(self, now: float):
        if self.mode == "raise":
            raise OSError("camera unplugged")
        r = self.inner.read(now)
        if self.mode == "shape":
            return type(r)(r.ids, r.poses[:, :2], r.seen)
        if self.mode == "nan":
            p = r.poses.copy()
            p[0] = np.nan
            return type(r)(r.ids, p, r.seen)
        return r

    def health(self) -> str:
        if self.mode == "raise":
            raise RuntimeError("no health either")
        return "ok"


def test_failing_pose_source_stops_robots_and_loop_survives() -> None:
    from swarmdeck.devices import ArenaConfig
    from swarmdeck.devices.simulated_robots import SimulatedRobots

    sim = SimulatedRobots(4, ArenaConfig(seed=1))
    src = _FlakySource(sim)
    loop = ControlLoop(LoopConfig(n_robots=4, behaviour="rendezvous"), source=src, sink=sim)
    assert not loop.tick().stopped
    for mode, text in (("raise", "camera unplugged"), ("shape", "expected (N,), (N, 3), (N,)")):
        src.mode = mode
        f = loop.tick()
        assert f.stopped and not f.seen.any() and any(text in a for a in f.alerts)
    src.mode = "nan"
    f = loop.tick()
    assert not f.seen[0] and f.seen[1:].all() and f.v[0] == 0.0 and np.all(np.isfinite(f.poses))
    src.mode = "ok"
    f = loop.tick()
    assert f.seen.all() and not f.alerts
