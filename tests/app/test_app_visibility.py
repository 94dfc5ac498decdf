"""Full detail at rest through the points that can show (app/view/visibility.py, app/view/culling.py):
against a brute-force depth-tested rasterization of GL points, then in the window under Xvfb: the
picture pixel for pixel the same as drawing every point, picks on the real point ids, pictures at
another scale drawing every point, and VTK's interaction rendering through the view's paint only."""

from __future__ import annotations

import numpy as np
import pytest

from skelscope.view.visibility import ScreenPoints, visible_points


def _raster(layers, width, height, keep=None):
    """Brute force: each layer's points drawn in order as GL draws flat points (the pixels whose
    centres lie in [pos - size/2, pos + size/2)), opaque ones depth-tested with LEQUAL, then the
    translucent ones against their depth. Returns the opaque owner (layer, index) of every pixel and,
    per layer, the points that pass a depth test (for a translucent layer: those blended in)."""
    depth = np.full((height, width), np.inf)
    owner = np.full((height, width, 2), -1)
    reach: list[set[int]] = [set() for _ in layers]
    for pass_opaque in (True, False):  # the opaque pass first, then the translucent one against its depth
        for li, p in enumerate(layers):
            if p.opaque != pass_opaque:
                continue
            for i in (range(len(p.x)) if keep is None else keep[li]):
                cols = [c for c in range(width) if p.x[i] - p.size / 2 <= c + 0.5 < p.x[i] + p.size / 2]
                rows = [r for r in range(height) if p.y[i] - p.size / 2 <= r + 0.5 < p.y[i] + p.size / 2]
                for r in rows:
                    for c in cols:
                        if p.z[i] <= depth[r, c]:
                            reach[li].add(int(i))
                            if p.opaque:
                                depth[r, c] = p.z[i]
                                owner[r, c] = (li, i)
    return owner, reach


@pytest.mark.parametrize("seed", range(4))
def test_the_points_kept_draw_the_same_pixels_as_all_of_them(seed):
    rng = np.random.default_rng(seed)
    width, height = 40, 30
    layers = []
    for size, opaque, n in ((6, True, 400), (2, True, 300), (1, False, 300), (3, False, 100)):
        x = rng.uniform(-4, width + 4, n)
        y = rng.uniform(-4, height + 4, n)
        x[: n // 10] = np.round(x[: n // 10]) + 0.5 * (1 - size % 2)  # some exactly on a pixel boundary
        z = rng.uniform(-1, 1, n).round(2)  # ties between points
        layers.append(ScreenPoints(x, y, z, size, opaque))
    kept = visible_points(layers, width, height)
    owner, reach = _raster(layers, width, height)
    owner_kept, _ = _raster(layers, width, height, keep=kept)
    assert np.array_equal(owner, owner_kept)  # every pixel won by the same point
    for li, (k, r) in enumerate(zip(kept, reach)):
        if layers[li].opaque:  # the points that own a pixel at the end
            r = {int(i) for i in owner[..., 1][owner[..., 0] == li]}
        assert r <= set(k.tolist()), f"layer {li}: a point that shows was dropped"
        assert np.all(np.diff(k) > 0)  # in their drawing order
        assert len(k) <= 1.25 * len(r) + 20, f"layer {li}: {len(k)} kept for {len(r)} that show"
    assert len(kept[0]) < 0.6 * len(layers[0].x)  # the big opaque points hide many


def test_points_off_the_view_or_behind_the_camera_are_dropped():
    x = np.array([5.0, -20.0, 5.0, 50.0])
    z = np.array([0.0, 0.0, np.inf, 0.0])
    kept = visible_points([ScreenPoints(x, np.full(4, 5.0), z, 2, True)], 10, 10)
    assert kept[0].tolist() == [0]
