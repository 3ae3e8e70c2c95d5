"""An unmodified Robotarium script that plots on its figure sees its drawing on the arena (issue 29 item 3; the
Robotarium 2.0: "anything that you plot within the boundaries … will be projected onto the testbed"): its
scatter markers, texts, lines and patches inside the arena become the step's annotations, sized in metres as
the script sized them; what lies outside (the title) and images are not drawn."""
from pathlib import Path

import numpy as np
import pytest

from swarmdeck.console.recording.reader import Recording
from swarmdeck.core.annotations import CIRCLE, POINT, POLYGON, POLYLINE, TEXT
from swarmdeck.devices.rps import rps_aliases
from swarmdeck.devices.runner import run_experiment

SCRIPT = Path(__file__).resolve().parents[1] / "data" / "rps" / "dd_barriers_with_plotting.py"
GOALS = [[1.0, 0.0], [-1.0, 0.0], [0.0, 0.7], [0.0, -0.7]]


def test_an_unmodified_rps_script_that_plots_is_recorded_with_its_drawing(tmp_path):
    from swarmdeck.console.recording.arena_recording import ArenaRecording

    out = tmp_path / "run.mcap"
    rec = ArenaRecording(out, script=SCRIPT, seed=1)
    result = run_experiment(SCRIPT, duration=3.0, seed=1, on_create=rec.on_create, on_step=rec.on_step)
    rec.close()
    assert result.ok, result.error
    frames = [f for _, f in Recording(out).frames()]
    a = frames[-1].annotations
    assert a is not None
    assert a.kinds.tolist() == [POINT] * 4 + [TEXT] * 4  # the 4 goal markers and their captions; no title, no image
    assert a.anchors()[:4].tolist() == GOALS and a.anchors()[4:].tolist() == GOALS
    assert a.texts[4:] == ("G0", "G1", "G2", "G3")
    assert a.sizes[:4] == pytest.approx(0.05)  # determine_marker_size(r, 0.1): 0.1 m across
    assert a.sizes[4:] == pytest.approx(0.1)  # determine_font_size(r, 0.1): 0.1 m tall
    assert len({tuple(c) for c in a.colors[:4].tolist()}) == 4  # matplotlib's colour cycle, one per scatter


def test_lines_patches_and_what_lies_outside():
    with rps_aliases():
        import matplotlib.patches as mpatches
        import rps.robotarium as robotarium

        r = robotarium.Robotarium(2, initial_conditions=np.array([[-0.5, 0.5], [0.0, 0.0], [0.0, 0.0]]),
                                  sim_in_real_time=False)
        r.arena  # noqa: B018 - a script reading its Arena's annotations asks for it first (figure projected from then on)
        r.axes.plot([-1.0, 0.0, 1.0], [0.5, 0.6, 0.5], "r-", linewidth=2)
        r.axes.plot([0.2], [0.2], "go")
        r.axes.add_patch(mpatches.Circle((0.3, -0.4), 0.2, color="blue", alpha=0.5))
        r.axes.add_patch(mpatches.Rectangle((-1.0, -0.8), 0.4, 0.3, fill=False, edgecolor="k"))
        r.axes.text(5.0, 5.0, "far away")  # outside the arena: not drawn
        r.axes.scatter([9.0], [9.0])  # outside: not drawn
        line, = r.axes.plot([0.0, 0.1], [0.0, 0.1], "m-")
        line.set_visible(False)  # hidden: not drawn
        r.get_poses()
        r.step()
        a = r.arena.last_annotations
        assert a.kinds.tolist() == [POLYLINE, POINT, CIRCLE, POLYGON]
        assert a.vertices[:3].tolist() == [[-1.0, 0.5], [0.0, 0.6], [1.0, 0.5]]
        assert a.colors[0].tolist() == [255, 0, 0, 255]
        assert a.anchors()[2].tolist() == pytest.approx([0.3, -0.4]) and a.sizes[2] == pytest.approx(0.2)
        assert a.filled[2] and a.colors[2, 3] == 128
        square = a.vertices[a.offsets[3]:a.offsets[4]]
        assert sorted(map(tuple, np.round(square, 6).tolist())) == [(-1.0, -0.8), (-1.0, -0.5), (-0.6, -0.8), (-0.6, -0.5)]
        assert not a.filled[3]
        r.axes.lines[0].remove()  # the script removes an artist: it is gone from the next step on
        r.get_poses()
        r.step()
        assert r.arena.last_annotations.kinds.tolist() == [POINT, CIRCLE, POLYGON]


def test_a_script_that_never_touches_the_figure_draws_nothing():
    with rps_aliases():
        import rps.robotarium as robotarium

        r = robotarium.Robotarium(2, sim_in_real_time=False)
        r.get_poses()
        r.step()
        assert len(r.arena.last_annotations) == 0 and r._figure is None
