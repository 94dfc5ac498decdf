"""A large missing region thinned out before its skelscope skeletonization (docs/repair.md "The
repair's cost"): the means of its points per cell of the finest grid with at most the cap's cells, and
the fill's skeletonization given those alone."""

from __future__ import annotations

import numpy as np

import skelcore
from skelcore import Params, shapes
from skelcore.curve import CurveSkeleton
from skelcore.skeleton_repair.findings import read_findings
from skelcore.skeleton_repair.thin_region import cells, thinned


def test_a_lattice_is_thinned_to_its_blocks_centres():
    """A 10 x 10 x 10 lattice of unit spacing and a cap of 125: a side of 2 (any in (1.8, 2.25])
    leaves 125 cells, 1.8 or less 216, so the means are the centres of its 2 x 2 x 2 blocks."""
    g = np.arange(10.0)
    pts = np.stack(np.meshgrid(g, g, g, indexing="ij"), axis=-1).reshape(-1, 3) + [100.0, -50.0, 3.0]
    out = thinned(pts[np.random.default_rng(1).permutation(len(pts))], 125)
    h = np.arange(5) * 2.0 + 0.5
    want = np.stack(np.meshgrid(h, h, h, indexing="ij"), axis=-1).reshape(-1, 3) + [100.0, -50.0, 3.0]
    assert out.shape == (125, 3)
    np.testing.assert_allclose(out, want, atol=1e-12)  # the cells' order is lexicographic
    assert thinned(pts, 124).shape[0] <= 124 and cells(pts, 2.0)[1] == 125 and cells(pts, 1.8)[1] == 216


def test_a_small_region_is_left_as_it_is_and_a_large_one_kept_near_the_cap():
    rng = np.random.default_rng(0)
    sphere = rng.normal(size=(20_000, 3))
    sphere /= np.linalg.norm(sphere, axis=1)[:, None]
    assert thinned(sphere[:500], 500) is not None and np.array_equal(thinned(sphere[:500], 500), sphere[:500])
    out = thinned(sphere, 3000)
    assert 1500 <= len(out) <= 3000  # the finest grid within the cap: near it, not far below
    assert np.array_equal(out, thinned(sphere, 3000))  # deterministic
    assert np.all(out >= sphere.min(axis=0) - 1e-12) and np.all(out <= sphere.max(axis=0) + 1e-12)
    r = np.linalg.norm(out, axis=1)
    assert r.max() <= 1.0 + 1e-12 and np.median(r) > 0.9  # means of near points: still on the shell


def test_the_fill_skeletonizes_a_region_on_at_most_the_cap(monkeypatch):
    """A tube whose curve stops halfway: the region's skeletonization (the fill after its axis curve)
    is given at most ``fill_points`` points, all of them without a cap."""
    from skelcore import skeleton
    from skelcore.skeleton_repair import fill

    s = shapes.cylinder(1500)
    half = s.curve_edges[(s.curve_edges < 11).all(axis=1)]
    curve = CurveSkeleton.from_raw(s.curve_vertices[:11], half)
    found = read_findings(skelcore.evaluate(s.cloud, curve=curve))
    n_region = int(np.count_nonzero(found.missing.region == found.missing.counted[0].id))
    assert n_region > 500
    given: list[int] = []
    real = skeleton.skeletonize

    def counting(pts, *a, **k):
        given.append(len(pts))
        return real(pts, *a, **k)

    monkeypatch.setattr(skeleton, "skeletonize", counting)
    capped = [a for a in fill.fill_missing(curve, found.missing, s.cloud, fill_points=300) if "skeletonized" in a.reason]
    whole = [a for a in fill.fill_missing(curve, found.missing, s.cloud) if "skeletonized" in a.reason]
    assert given[0] <= 300 and given[-1] == n_region and capped and whole
    assert Params().repair_fill_points >= 1000
