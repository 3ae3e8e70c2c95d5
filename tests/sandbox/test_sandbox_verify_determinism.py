"""Same seeds, same report, bit for bit: serial, a local pool of 2, and Ray (a local cluster with num_cpus=2)."""
import json
import textwrap

import pytest

from swarmdeck.console.sandbox.confinement import probe
from swarmdeck.console.sandbox.executors import LocalPoolExecutor, RayExecutor, SerialExecutor
from swarmdeck.console.sandbox.verification import VerificationConfig, verify

pytestmark = pytest.mark.skipif(probe() is not None, reason=f"no confinement here: {probe()}")

SCRIPT = """
def experiment(arena):
    while True:
        p = arena.positions()
        arena.set_velocities(-3.0 * (p - p.mean(axis=0)))
        arena.step()
"""


@pytest.mark.slow
def test_serial_pool_and_ray_give_identical_json(tmp_path):
    ray = pytest.importorskip("ray")
    script = tmp_path / "rendezvous.py"
    script.write_text(textwrap.dedent(SCRIPT))
    config = VerificationConfig(n_robots=6, duration=3.0, runs=1, seed=11)
    progress = []
    serial = verify([script], config, SerialExecutor(), on_progress=progress.append)
    assert [p.done for p in progress] == [1, 2] and all(p.total == 2 for p in progress)
    text = json.dumps(serial.to_dict(), sort_keys=True)
    assert any(r["contacts"]["count"] for r in serial.scripts[0]["runs"])  # floats worth comparing
    assert json.dumps(verify([script], config, LocalPoolExecutor(2)).to_dict(), sort_keys=True) == text
    try:
        assert json.dumps(verify([script], config, RayExecutor("local", num_cpus=2)).to_dict(), sort_keys=True) == text
    finally:
        ray.shutdown()
    other = verify([script], VerificationConfig(n_robots=6, duration=3.0, runs=1, seed=12), SerialExecutor())
    assert json.dumps(other.to_dict(), sort_keys=True) != text  # the seed matters
