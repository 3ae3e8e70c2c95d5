"""The renderer-neutral picture of a Frame (``swarmdeck.console.picture``): its rules live once — the changed
threshold, the active-pair guard, the D_s fallback, labels and glyphs up to how many robots — it never changes
the Frame, and the portal's live view receives its palette and glyph sizes rather than hard-coding them."""
from __future__ import annotations

import numpy as np
import pytest

from swarmdeck.console.picture import PictureStyle, heatmap, picture_of
from swarmdeck.console.picture import colours as pal
from swarmdeck.console.picture.shapes import CHANGED_RING, VIRTUAL_RING_RADIUS
from swarmdeck.console.portal.live import scene_message
from swarmdeck.console.recording.foxglove import FoxgloveConfig
from swarmdeck.console.runtime.frame import BarrierFrame, Frame
from swarmdeck.core.constants import ROBOT_RADIUS
from swarmdeck.coverage import GaussianMixture


def _frame(n: int = 4, barrier: BarrierFrame | None = None, **kw) -> Frame:
    rng = np.random.default_rng(3)
    poses = np.column_stack((rng.uniform(-1.4, 1.4, n), rng.uniform(-0.8, 0.8, n), rng.uniform(-3, 3, n)))
    return Frame(tick=1, time=0.0, poses=poses, ids=np.arange(n), nominal=rng.normal(0, 0.1, (n, 2)),
                 safe=rng.normal(0, 0.1, (n, 2)), v=np.zeros(n), w=np.zeros(n), barrier=barrier, **kw)


def test_changed_means_more_than_the_threshold_and_only_for_a_whole_intervention() -> None:
    f = _frame(barrier=BarrierFrame(intervention=[0.0, 1e-3, 1.0001e-3, 0.2]))
    pic = picture_of(f)
    assert pic.changed.tolist() == [False, False, True, True]
    assert [tuple(c) for c in pic.colors[2:]] == [tuple(pal.CHANGED)] * 2 and tuple(pic.colors[0]) == tuple(pal.ROBOT)
    assert picture_of(f, PictureStyle(changed_threshold=0.1)).changed.tolist() == [False, False, False, True]
    short = picture_of(_frame(barrier=BarrierFrame(intervention=[0.5, 0.5])))  # 2 values for 4 robots: none
    assert not short.changed.any() and (short.colors == pal.ROBOT).all()


def test_a_pair_naming_a_missing_robot_draws_no_pair_at_all() -> None:
    good = picture_of(_frame(barrier=BarrierFrame(active_pairs=[[0, 1], [2, 3]], active_h=[-0.5, 0.05])))
    assert good.pairs.tolist() == [[0, 1], [2, 3]]
    assert good.pair_colors.tolist() == [[230, 40, 20], [230, 130, 30]]
    bad = picture_of(_frame(barrier=BarrierFrame(active_pairs=[[0, 1], [2, 4]], active_h=[-0.5, 0.05])))
    assert bad.pairs.shape == (0, 2) and bad.pair_h.shape == (0,) and bad.pair_colors.shape == (0, 3)


def test_the_safety_ring_is_half_the_barriers_distance_or_half_the_default() -> None:
    assert picture_of(_frame()).ring_radius == pytest.approx(0.085)  # no barrier: D_s = 0.17 m (REFERENCE §3)
    assert picture_of(_frame(), PictureStyle(safety_distance=0.3)).ring_radius == pytest.approx(0.15)
    assert picture_of(_frame(barrier=BarrierFrame(safety_distance=0.2))).ring_radius == pytest.approx(0.1)


def test_arrows_labels_and_glyphs_follow_the_style() -> None:
    f = _frame(n=5)
    pic = picture_of(f, PictureStyle(arrow_scale=2.0, label_offset=0.1, max_labels=5, max_glyphs=4))
    np.testing.assert_array_equal(pic.nominal_tips, f.points + 2.0 * f.nominal)
    np.testing.assert_array_equal(pic.safe_tips, f.points + 2.0 * f.safe)
    np.testing.assert_array_equal(pic.label_xy, f.poses[:, :2] + [0.0, 0.1])
    assert pic.labelled and not pic.glyphs
    assert FoxgloveConfig().max_labels == PictureStyle().max_labels  # one default for every renderer


def test_the_picture_is_read_only_and_leaves_the_frame_alone() -> None:
    f = _frame(barrier=BarrierFrame(active_pairs=[[0, 1]], active_h=[0.0], intervention=[0, 0.5, 0, 0]),
               is_virtual=[False, False, True, False], seen=[True, False, True, True], run_state="paused")
    before = f.to_dict()
    pic = picture_of(f)
    assert f.to_dict() == before
    for name in ("colors", "changed", "virtual", "pairs", "pair_colors", "points", "nominal_tips", "label_xy"):
        with pytest.raises(ValueError):
            getattr(pic, name)[...] = 0
    paused = pal.PAUSED.astype(float)
    assert tuple(pic.colors[0]) == tuple(pal.PAUSED) and tuple(pic.colors[1]) == tuple(pal.UNSEEN)
    assert tuple(pic.colors[2]) == tuple(np.round(paused * 0.45 + 255 * 0.55).astype(np.uint8))  # virtual: pale


def test_goals_only_for_goto_and_the_heat_map_only_with_a_density() -> None:
    assert picture_of(_frame()).goals.shape == (0, 2) and picture_of(_frame()).heat_map(10.0) is None
    g = GaussianMixture(0.01, mu=[[1.0, 0.5]], sigma=[0.2], weight=[1.0])
    f = _frame(behaviour="goto", density=g)
    pic = picture_of(f)
    assert pic.goals.shape == (4, 2)
    np.testing.assert_array_equal(pic.heat_map(10.0), heatmap(g, f.bounds, 10.0))


def test_the_live_view_gets_the_pictures_palette_and_glyph_sizes() -> None:
    m = scene_message(_frame(), 1)
    assert m["robot_radius"] == ROBOT_RADIUS and m["rings"] == {"changed": CHANGED_RING, "virtual": VIRTUAL_RING_RADIUS}
    assert m["palette"]["changed"] == pal.hex_colors(pal.CHANGED)[0] == "#ff8c00"
    assert m["palette"]["voronoi"] == pal.hex_colors(np.array(pal.VORONOI))[0]
    assert m["palette"]["floor"] == pal.hex_colors(pal.LUT[0])[0]
