"""Decentralised scripts run where every script runs: in the sandbox (`swarmdeck run --sandbox`: a controller that
reads another robot's pose is refused there too, named and counted, and the run goes on) and as built-in examples
(`swarmdeck example decentralised-rendezvous`, `decentralised-formation`)."""
from __future__ import annotations

import textwrap

from swarmdeck.console.cli import main

PEEK = """
    import numpy as np
    from swarmdeck.devices import Arena
    from swarmdeck.devices.decentralised import Decentralised
    from swarmdeck.network import KNearestTopology, NetworkConfig

    arena = Arena()

    def robot(i, view):
        if i == 0:
            return arena.poses()[1, :2] - view.position  # robot 0 peeks at robot 1
        view.broadcast(view.position)
        return np.zeros(2)

    run = Decentralised(arena, robot, NetworkConfig(topology=KNearestTopology(2)))  # linked wherever they start
    try:
        while True:
            run.step()
    finally:
        print("isolation errors:", run.errors["IsolationError"], "delivered:", run.network.stats["delivered"])
        print(run.events[0])
"""


def test_a_peeking_controller_is_refused_inside_the_sandbox_and_the_run_goes_on(tmp_path, capsys):
    script = tmp_path / "peek.py"
    script.write_text(textwrap.dedent(PEEK))
    assert main(["run", "--sandbox", str(script), "--robots", "3", "--duration", "0.5", "--seed", "4"]) == 0
    out = capsys.readouterr().out
    assert "isolation errors: 16" in out  # every tick of 0.5 s (16 steps) refused robot 0
    assert "robot 0's controller read arena.poses()" in out
    assert "delivered: 0" not in out  # the other robots talked meanwhile


def test_the_decentralised_examples_are_built_in(capsys):
    assert main(["example", "decentralised-rendezvous", "--robots", "4", "--duration", "2", "--seed", "1"]) == 0
    out = capsys.readouterr().out
    assert "final spread (m)" in out and "controller errors: 0" in out
    assert main(["example", "decentralised-formation", "--robots", "5", "--duration", "2", "--seed", "1"]) == 0
    assert "largest edge-length error (m)" in capsys.readouterr().out
