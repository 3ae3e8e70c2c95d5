"""The communication-graph layer of the picture: the robots' links and how busy each is (issue 28 item 2).

:func:`network_layer` turns a Frame's ``network`` (:class:`~swarmdeck.console.runtime.network_frame.NetworkFrame`)
into segments between the robots' centres, one per undirected pair that has a link either way, coloured from
:data:`~.colours.LINK_IDLE` (a link nothing crossed this tick) to :data:`~.colours.LINK_BUSY` (the pair's
messages per second at or above ``PictureStyle.network_rate_full``). Renderers draw ``segments`` with
``colors``; ``rate`` is there for labels and widths.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from swarmdeck.console.picture.colours import LINK_BUSY, LINK_IDLE
from swarmdeck.console.picture.style import PictureStyle
from swarmdeck.console.runtime.frame import Frame

__all__ = ["NetworkLayer", "link_colors", "network_layer"]


@dataclass(frozen=True)
class NetworkLayer:
    """``pairs`` (P, 2) robot indices i < j with a link either way; ``segments`` (P, 2, 2) m between their
    centres; ``rate`` (P,) messages/s over both directions; ``colors`` (P, 3) uint8; ``busy`` (P,) rate > 0."""

    pairs: NDArray[np.int64]
    segments: NDArray[np.float64]
    rate: NDArray[np.float64]
    colors: NDArray[np.uint8]
    busy: NDArray[np.bool_]


def link_colors(rate: NDArray[np.float64], rate_full: float) -> NDArray[np.uint8]:
    """(P, 3) colours by messages per second: :data:`LINK_IDLE` at 0 → :data:`LINK_BUSY` at ≥ ``rate_full``."""
    s = np.clip(np.asarray(rate, dtype=float) / rate_full, 0.0, 1.0)[:, None]
    idle, busy = np.asarray(LINK_IDLE, dtype=float), np.asarray(LINK_BUSY, dtype=float)
    return np.round(idle * (1.0 - s) + busy * s).astype(np.uint8).reshape(-1, 3)


def network_layer(frame: Frame, style: PictureStyle) -> NetworkLayer | None:
    """The layer of ``frame``, or None when it has no network, the style hides it, or a link names a robot the
    Frame lacks."""
    net = frame.network
    if net is None or not style.show_network:
        return None
    links = np.asarray(net.links, dtype=np.int64).reshape(-1, 2)
    if links.size and int(links.max()) >= frame.n:
        return None
    undirected = np.sort(links, axis=1)
    pairs, inverse = np.unique(undirected, axis=0, return_inverse=True) if len(links) else (
        np.empty((0, 2), dtype=np.int64), np.empty(0, dtype=np.int64))
    rate = np.zeros(len(pairs))
    np.add.at(rate, np.asarray(inverse).reshape(-1), net.rate)
    xy = frame.poses[:, :2]
    segments = np.stack((xy[pairs[:, 0]], xy[pairs[:, 1]]), axis=1) if len(pairs) else np.zeros((0, 2, 2))
    out = NetworkLayer(pairs=pairs.astype(np.int64), segments=segments, rate=rate,
                       colors=link_colors(rate, style.network_rate_full), busy=rate > 0)
    for a in (out.pairs, out.segments, out.rate, out.colors, out.busy):
        a.flags.writeable = False
    return out
