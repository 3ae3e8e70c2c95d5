"""A Robotarium script's hollow markers (markerfacecolor "none", as rps 2.0's barriers_with_plotting.py draws its
goals) become outlined points in the edge colour; an invisible colour draws nothing (it crashed the figure's
conversion before: to_rgba_array("none") has no rows)."""
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from swarmdeck.core.bounds import DEFAULT_BOUNDS  # noqa: E402
from swarmdeck.devices.rps.figure_annotations import figure_annotations  # noqa: E402


def test_hollow_markers_are_outlined_points_in_the_edge_colour():
    fig, ax = plt.subplots()
    try:
        ax.plot([0.1, 0.5], [0.2, -0.3], "o", markerfacecolor="none", markeredgecolor="red", markersize=10)
        ax.plot([0.0, 0.2], [0.0, 0.1], color="none")
        ann = figure_annotations(ax, DEFAULT_BOUNDS)
    finally:
        plt.close(fig)
    assert len(ann) == 2
    np.testing.assert_array_equal(ann.colors[:, :3], [[255, 0, 0]] * 2)
    assert not ann.filled.any()
