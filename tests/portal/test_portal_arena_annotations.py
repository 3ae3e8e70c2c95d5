"""What a job's sandboxed script draws reaches the portal arena's Frames (issue 29 item 3): the plant on the
console loop hands the script's ``draw`` messages to the loop's behaviour (``SandboxCommands.draw``), whose
annotations each tick's Frame carries — capped there (NaN refused, clipped into the arena), and replaced by
the script's next drawing."""
import numpy as np

from swarmdeck.console.portal.runner import SandboxCommands
from swarmdeck.console.runtime.loop import ControlLoop, LoopConfig
from swarmdeck.console.sandbox.plant import SandboxPlant
from swarmdeck.core.annotations import CIRCLE, POINT, TEXT, Annotations


def test_the_scripts_drawing_is_in_the_loops_frames_capped():
    loop = ControlLoop(LoopConfig(n_robots=3, seed=2))
    commands = SandboxCommands(loop.config.bounds, on_warning=loop.post)
    loop.use_behaviour(commands)
    loop.run()
    plant = SandboxPlant.on_loop(loop, commands, duration=10.0, pacer=None)
    plant.draw(Annotations(kinds=[POINT, CIRCLE, TEXT], offsets=[0, 1, 2, 3],
                           vertices=[[np.nan, 0.0], [5.0, 0.0], [0.0, 0.5]], sizes=[0.01, 0.1, 0.05],
                           colors=[[0, 0, 0, 255]] * 3, filled=[True, False, False], texts=("", "", "hi")))
    plant.apply(np.zeros((3, 2)))
    a = loop.latest.annotations
    assert a.kinds.tolist() == [CIRCLE, TEXT] and a.anchors()[0].tolist() == [1.6, 0.0] and a.texts[1] == "hi"
    assert commands.draw.warnings == 2  # the NaN point refused, the circle clipped: counted, in the Frame's events
    assert any("NaN/inf" in e for e in loop.latest.events) and any("outside the arena" in e for e in loop.latest.events)
    plant.draw(Annotations())  # the script cleared its drawing
    plant.apply(np.zeros((3, 2)))
    assert loop.latest.annotations is None
