"""The rps facade projects a script's matplotlib figure onto the arena only when something reads the arena's
annotations (Arena.annotations_read): a recording, robots behind a trust boundary, a per-step hook, or the script
asking for ``r.arena``. A headless ``swarmdeck run`` without ``--record`` shows no figure, so it skips the
projection (about 1 ms a step for the plotting examples); swarmdeck's own progress bar does not count as a reader."""
from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from swarmdeck.devices.arena import Arena
from swarmdeck.devices.runner import progress_bar, run_experiment

SCRIPT = textwrap.dedent("""
    import numpy as np
    import rps.robotarium as robotarium

    r = robotarium.Robotarium(number_of_robots=2, show_figure=True, sim_in_real_time=False,
                              initial_conditions=np.array([[-0.5, 0.5], [0.0, 0.0], [0.0, 0.0]]))
    r.axes.plot([0.2], [0.2], "go")
    for _ in range(3):
        r.get_poses()
        r.set_velocities(np.arange(2), np.zeros((2, 2)))
        r.step()
    r.call_at_scripts_end()
""")


@pytest.fixture()
def script(tmp_path: Path) -> Path:
    path = tmp_path / "plots.py"
    path.write_text(SCRIPT)
    return path


def test_nothing_reads_the_annotations_so_the_figure_is_not_projected(script: Path) -> None:
    result = run_experiment(script, duration=1.0, seed=1, rps=True)
    assert result.ok, result.error
    arena = result.arenas[0]
    assert not arena.annotations_read and len(arena.last_annotations) == 0


def test_a_per_step_hook_reads_them(script: Path) -> None:
    seen: list[int] = []
    result = run_experiment(script, duration=1.0, seed=1, rps=True, on_step=lambda a: seen.append(len(a.last_annotations)))
    assert result.ok, result.error
    assert seen == [1, 1, 1]  # the green marker, every step


def test_the_progress_bar_does_not_read_them() -> None:
    class Tty:
        def isatty(self) -> bool:
            return True

        def write(self, s: str) -> int:
            return len(s)

        def flush(self) -> None:
            pass

    import sys

    saved = sys.stderr
    sys.stderr = Tty()  # type: ignore[assignment]
    try:
        on_step, close = progress_bar(1.0)
    finally:
        sys.stderr = saved
    assert on_step is not None and getattr(on_step, "reads_annotations", True) is False
    close()


def test_a_recording_reads_them(script: Path, tmp_path: Path) -> None:
    from swarmdeck.console.recording.arena_recording import ArenaRecording
    from swarmdeck.console.recording.reader import Recording

    out = tmp_path / "run.mcap"
    rec = ArenaRecording(out, script=script, seed=1)
    result = run_experiment(script, duration=1.0, seed=1, rps=True, on_create=rec.on_create, on_step=rec.on_step)
    rec.close()
    assert result.ok, result.error
    frames = [f for _, f in Recording(out).frames()]
    assert frames[-1].annotations is not None and len(frames[-1].annotations) == 1


def test_robots_behind_a_trust_boundary_read_them() -> None:
    class Sink:
        def send_annotations(self, ann: object) -> None:
            pass

    arena = Arena(2, duration=1.0)
    assert not arena.annotations_read
    arena.backend = Sink()  # type: ignore[assignment]  # what the sandbox's child sink offers
    assert arena.annotations_read
