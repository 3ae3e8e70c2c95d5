"""At thousands of robots the console's viewer draws the scene at most every draw_interval(N) s (thinned), the
newest Frame each time; below THIN_FROM robots every Frame it gets is drawn as before."""
from __future__ import annotations

import numpy as np
import pytest
import viser

from swarmdeck.console.portal.operator_view import OperatorView
from swarmdeck.console.runtime.frame import Frame
from swarmdeck.console.runtime.loop import ControlLoop, DensityParams, LoopConfig
from swarmdeck.console.web.app import THIN_FROM, FrameViewer, draw_interval
from swarmdeck.console.web.scene import ArenaScene


@pytest.fixture(scope="module")
def scene():
    s = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    yield ArenaScene(s)
    s.stop()


def test_draw_interval_thins_only_from_thousands_of_robots() -> None:
    assert draw_interval(12) == 0.0 and draw_interval(THIN_FROM - 1) == 0.0
    assert draw_interval(5000) == pytest.approx(0.25) and draw_interval(10000) == pytest.approx(0.5)
    with pytest.raises(ValueError, match="min_interval"):
        FrameViewer(None, min_interval=-1.0)  # type: ignore[arg-type]


def test_a_thinned_viewer_waits_then_draws_the_newest_frame(scene) -> None:
    now = [100.0]
    viewer = FrameViewer(scene, min_interval=0.25, clock=lambda: now[0])
    loop = ControlLoop(LoopConfig(seed=2, n_robots=5, density=DensityParams(moving=False)))
    frames = [loop.tick() for _ in range(4)]
    assert viewer.until_next() == 0.0                     # nothing drawn yet: at once
    viewer.offer(frames[0])
    assert viewer.draw_pending() is frames[0]
    now[0] = 100.1
    assert viewer.until_next() == pytest.approx(0.15)     # 0.25 s after the last draw
    for f in frames[1:]:
        viewer.offer(f)
    now[0] = 100.25
    assert viewer.until_next() == 0.0
    assert viewer.draw_pending() is frames[-1] and viewer.skipped == 2


def test_an_unthinned_viewer_never_waits(scene) -> None:
    viewer = FrameViewer(scene, clock=lambda: 5.0)
    viewer.offer(ControlLoop(LoopConfig(seed=2, n_robots=3)).tick())
    viewer.draw_pending()
    assert viewer.until_next() == 0.0


def test_a_stopped_thinned_viewer_ends_while_it_waits(scene) -> None:
    viewer = FrameViewer(scene, min_interval=3600.0).start()  # would wait an hour after its first draw
    viewer.offer(ControlLoop(LoopConfig(seed=2, n_robots=3)).tick())
    viewer.offer(ControlLoop(LoopConfig(seed=3, n_robots=3)).tick())
    viewer.stop()                                               # ServiceThread.stop joins with its timeout
    assert not viewer._service.alive


def _frame(n: int, tick: int = 0) -> Frame:
    z = np.zeros(n)
    return Frame(tick=tick, time=0.0, poses=np.zeros((n, 3)), ids=np.arange(n), nominal=np.zeros((n, 2)),
                 safe=np.zeros((n, 2)), v=z, w=z)


def test_a_viewer_thinned_by_each_frames_robot_count(scene) -> None:
    """The portal's operator view does not know a job's robot count in advance: it thins by the Frame it drew
    (it drew every Frame of a 5000-robot job before, holding the GIL the arena's loop needs)."""
    now = [10.0]
    viewer = FrameViewer(scene, clock=lambda: now[0], interval_for=draw_interval)
    viewer.offer(_frame(5))
    viewer.draw_pending()
    assert viewer.until_next() == 0.0                     # a few robots: every Frame
    viewer.offer(_frame(THIN_FROM + 500, tick=1))
    viewer.draw_pending()
    assert viewer.until_next() == pytest.approx(draw_interval(THIN_FROM + 500))
    now[0] += draw_interval(THIN_FROM + 500)
    assert viewer.until_next() == 0.0


def test_the_operator_view_thins_by_robot_count() -> None:
    view = OperatorView(port=0)
    try:
        assert view.viewer.interval_for is draw_interval
    finally:
        view.close()
