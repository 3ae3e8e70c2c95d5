"""Loading a second script while a script behaviour runs switches to the new script, never to
coverage in between (issue 14, item 16: the recording showed "behaviour: script:…" then
"behaviour: coverage" in the same frame)."""
from __future__ import annotations

import pytest
import viser

from swarmdeck.console.runtime.loop import ControlLoop, DensityParams, LoopConfig
from swarmdeck.console.web.gui import ConsoleGui
from swarmdeck.console.web.scene import ArenaScene

SCRIPT = "import numpy as np\ndef behaviour(poses, t):\n    return np.full((len(poses), 2), {v})\n"


@pytest.fixture
def console():
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    loop = ControlLoop(LoopConfig(seed=2, n_robots=4, density=DensityParams(moving=False)))
    scene = ArenaScene(server, loop.config.bounds)
    gui = ConsoleGui(server, loop, scene)
    gui.update(loop.tick(), force=True)
    yield loop, gui
    server.stop()


def test_second_script_replaces_the_first_without_a_detour(console, tmp_path) -> None:
    loop, gui = console
    first, second = tmp_path / "first.py", tmp_path / "second.py"
    first.write_text(SCRIPT.format(v=0.01))
    second.write_text(SCRIPT.format(v=-0.01))
    for path in (first, second):
        gui.script_path.value = str(path)
        gui.load_script.value = True
        frame = loop.tick()
        gui.update(frame, force=True)
        assert frame.behaviour == f"script:{path}"
        assert gui.behaviour.value == f"script:{path}"
    switches = [e for e in frame.events if e.startswith("behaviour:")]
    assert switches == [f"behaviour: script:{second}"], frame.events
    assert gui.behaviour.options[-1] == f"script:{second}"
    assert f"script:{first}" not in gui.behaviour.options
