"""Screen-space visibility of big point layers: which points can show in a frame at all.

A flat GL point of integer size ``s`` covers an ``s`` x ``s`` square of pixels whose corner (its
anchor) follows from its display position; at rest a frame of 2M points has far fewer pixels, so most
points lose every depth test. The opaque points' depth per pixel is a scatter of each point to its
anchor and a running minimum over ``s`` anchors; a point can show when its depth is at most the
largest of those depths over its own square. Drawing only those, in their order, gives the same
image: every pixel's depth test is won by the same point (ties kept, with a depth margin).
A point within ``EDGE_PX`` (or its own rounding bound) of a pixel boundary (GL could round it either
way) is an occluder of nothing, and is tested on either anchor.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import maximum_filter1d, minimum_filter1d

__all__ = ["ScreenPoints", "visible_points", "EDGE_PX", "DEPTH_MARGIN"]

EDGE_PX = 0.01
"""Display positions this close to a pixel boundary may be rasterized on either side of it."""
DEPTH_MARGIN = 1e-5
"""Points this much farther (normalized depth, -1..1) than the front one still count as in front:
GL's depth buffer (24 bits) and its float32 vertex transform round at about a tenth of this."""


@dataclass
class ScreenPoints:
    """One layer projected: display ``x``, ``y`` (pixels, origin bottom left), normalized depth ``z``
    (inf behind the camera), its GL point ``size`` in pixels, and whether it hides what lies behind
    (``opaque``: a translucent layer is tested against the opaque ones but hides nothing); ``edge``:
    how far (pixels) a display position may be from where GL rounds it, at least EDGE_PX."""

    x: np.ndarray
    y: np.ndarray
    z: np.ndarray
    size: int
    opaque: bool
    edge: np.ndarray | float = EDGE_PX


def _anchors(pos: np.ndarray, size: int, edge: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """The first pixel a point's square may start at, rounded down and up within ``edge``: a square of
    ``size`` pixels centred at ``pos`` covers the pixels whose centres lie in [pos - size/2, pos + size/2)."""
    far = np.float32(1e6)  # off the view either way; keeps the anchors' int32 exact (NaN: dropped by its depth)
    start = np.clip(pos, -far, far) - np.float32(0.5 * size + 0.5)
    edge = np.clip(np.asarray(edge, dtype=np.float32), np.float32(EDGE_PX), far)
    with np.errstate(invalid="ignore"):
        return np.ceil(start - edge).astype(np.int32), np.ceil(start + edge).astype(np.int32)


def visible_points(layers: list[ScreenPoints], width: int, height: int) -> list[np.ndarray]:
    """For each layer, the sorted indices of its points that can win a pixel of a ``width`` x ``height``
    view (the rest lose every depth test to an opaque point, or lie off the view)."""
    pad = max([p.size for p in layers] + [1]) + 1
    shape = (height + 2 * pad, width + 2 * pad)
    front = np.full(shape, np.inf, dtype=np.float32)  # the opaque points' depth per pixel
    anchors = []
    for p in layers:
        xa, xb = _anchors(np.asarray(p.x, dtype=np.float32), p.size, p.edge)
        ya, yb = _anchors(np.asarray(p.y, dtype=np.float32), p.size, p.edge)
        on = (xb > -p.size) & (xa < width) & (yb > -p.size) & (ya < height) & np.isfinite(p.z)
        anchors.append((xa, xb, ya, yb, on))
        if p.opaque:
            sure = on & (xa == xb) & (ya == yb)
            grid = np.full(shape, np.inf, dtype=np.float32)
            np.minimum.at(grid.ravel(), (ya[sure] + pad).astype(np.int64) * shape[1] + xa[sure] + pad,
                          p.z[sure].astype(np.float32))
            for axis in (0, 1):  # a pixel's depth: the least over the anchors whose square covers it
                grid = minimum_filter1d(grid, p.size, axis=axis, mode="constant", cval=np.inf,
                                        origin=(p.size - 1) // 2)
            np.minimum(front, grid, out=front)
    front[:pad], front[pad + height:], front[:, :pad], front[:, pad + width:] = -np.inf, -np.inf, -np.inf, -np.inf
    kept = []
    for p, (xa, xb, ya, yb, on) in zip(layers, anchors):
        deepest = front
        for axis in (0, 1):  # an anchor's square: the largest front depth over it
            deepest = maximum_filter1d(deepest, p.size, axis=axis, mode="constant", cval=-np.inf,
                                       origin=-(p.size // 2))
        idx = np.flatnonzero(on)
        flat = deepest.ravel()
        reach = flat[(ya[idx] + pad).astype(np.int64) * shape[1] + xa[idx] + pad]
        edge = np.flatnonzero((xa[idx] != xb[idx]) | (ya[idx] != yb[idx]))  # either square may be drawn
        if len(edge):
            e = idx[edge]
            rows = [(y + pad).astype(np.int64) * shape[1] for y in (ya[e], yb[e])]
            reach[edge] = np.max([flat[r + x + pad] for r in rows for x in (xa[e], xb[e])], axis=0)
            wide = (xb[e] - xa[e] > 1) | (yb[e] - ya[e] > 1)  # squares between the two: kept outright
            reach[edge[wide]] = np.inf
        kept.append(idx[p.z[idx] <= reach + DEPTH_MARGIN])
    return kept
