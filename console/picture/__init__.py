"""One renderer-neutral picture of a Frame (issue 25 item 2): what to draw, not how.

Below both ``console.web`` and ``console.recording`` (it imports neither): the viser
scene, the MP4 video, the Foxglove channels and the portal's live view are thin
backends over :func:`picture_of`. ``colours`` is the palette, ``style`` the shared
rules (:class:`PictureStyle`), ``heat`` the density image, ``picture`` the
:class:`Picture` of a Frame.
"""
from swarmdeck.console.picture.colours import LUT, hex_colors, pair_colors
from swarmdeck.console.picture.heat import heatmap
from swarmdeck.console.picture.picture import (
    Picture,
    active_pairs,
    cell_shades,
    changed_mask,
    picture_of,
    robot_colors,
    safety_distance,
)
from swarmdeck.console.picture.style import PictureStyle

__all__ = [
    "LUT", "Picture", "PictureStyle", "active_pairs", "cell_shades", "changed_mask", "heatmap", "hex_colors",
    "pair_colors", "picture_of", "robot_colors", "safety_distance",
]
