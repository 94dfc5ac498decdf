"""Fitzgibbon / Halir-Flusser ellipse fit (docs/metrics.md 3, curve centeredness)."""

from __future__ import annotations

import numpy as np
import pytest

from skelcore.metrics.ellipse_fit import fit_ellipse, fit_ellipses


def _ellipse(center, a, b, angle, t):
    c, s = np.cos(angle), np.sin(angle)
    x, y = a * np.cos(t), b * np.sin(t)
    return np.column_stack([center[0] + c * x - s * y, center[1] + s * x + c * y])


@pytest.mark.parametrize(
    "center, a, b, angle",
    [((0.0, 0.0), 2.0, 1.0, 0.0), ((5.0, -3.0), 3.0, 0.5, 0.7), ((-100.0, 40.0), 0.02, 0.015, -1.2)],
)
def test_recovers_rotated_off_centre_ellipse_exactly(center, a, b, angle):
    t = np.random.default_rng(3).uniform(0, 2 * np.pi, 40)
    fit = fit_ellipse(_ellipse(center, a, b, angle, t))
    assert fit is not None
    c, axes, ang = fit
    np.testing.assert_allclose(c, center, rtol=0, atol=1e-8 * a)
    np.testing.assert_allclose(axes, [a, b], rtol=1e-8)
    assert abs(np.sin(ang - angle)) < 1e-8


def test_recovers_ellipse_from_five_points():
    t = np.array([0.1, 1.3, 2.0, 3.9, 5.0])
    c, axes, _ = fit_ellipse(_ellipse((1.0, 2.0), 4.0, 1.5, 0.3, t))
    np.testing.assert_allclose(c, [1, 2], atol=1e-8)
    np.testing.assert_allclose(axes, [4, 1.5], rtol=1e-8)


def test_recovers_ellipse_from_a_short_arc():
    t = np.linspace(0.2, 1.4, 30)
    c, axes, _ = fit_ellipse(_ellipse((0.5, 0.5), 2.0, 1.0, 0.4, t))
    np.testing.assert_allclose(c, [0.5, 0.5], atol=1e-6)
    np.testing.assert_allclose(axes, [2, 1], rtol=1e-6)


def test_circle_has_equal_semi_axes():
    t = np.linspace(0, 2 * np.pi, 17, endpoint=False)
    c, axes, _ = fit_ellipse(np.column_stack([1 + 0.3 * np.cos(t), -2 + 0.3 * np.sin(t)]))
    np.testing.assert_allclose(c, [1, -2], atol=1e-10)
    np.testing.assert_allclose(axes, [0.3, 0.3], rtol=1e-9)


def test_noisy_circle_centre_is_close():
    rng = np.random.default_rng(11)
    t = rng.uniform(0, 2 * np.pi, 300)
    xy = np.column_stack([np.cos(t), np.sin(t)]) + rng.normal(scale=0.01, size=(300, 2))
    c, axes, _ = fit_ellipse(xy)
    assert np.linalg.norm(c) < 0.01
    np.testing.assert_allclose(axes, [1, 1], atol=0.02)


def test_collinear_points_give_none():
    x = np.linspace(-1, 3, 12)
    assert fit_ellipse(np.column_stack([x, 2 * x + 1])) is None


def test_coincident_points_give_none():
    assert fit_ellipse(np.ones((8, 2))) is None


def test_fewer_than_five_points_give_none():
    t = np.array([0.0, 1.0, 2.0, 3.0])
    assert fit_ellipse(np.column_stack([np.cos(t), np.sin(t)])) is None


def test_hyperbola_points_still_give_a_real_ellipse():
    # the constraint 4ac - b^2 = 1 forces an ellipse whatever the data (Fitzgibbon's key property)
    x = np.array([0.5, 1.0, 2.0, 3.0, -0.5, -1.0, -2.0, -3.0])
    fit = fit_ellipse(np.column_stack([x, 1 / x]))
    assert fit is not None
    c, axes, _ = fit
    np.testing.assert_allclose(c, [0, 0], atol=1e-9)  # symmetric data, symmetric fit
    assert np.all(axes > 0)


def test_two_parallel_lines_give_none():
    x = np.linspace(0, 1, 10)
    assert fit_ellipse(np.column_stack([np.r_[x, x], np.r_[np.zeros(10), np.ones(10)]])) is None


def test_rejects_wrong_shape():
    with pytest.raises(ValueError):
        fit_ellipse(np.zeros((6, 3)))


def test_batched_fits_equal_one_by_one():
    """fit_ellipses (the batch curve centeredness uses) = fit_ellipse of each set alone, bit for bit,
    including the sets it must reject: too few points, collinear, a NaN point, coincident points,
    hyperbola-like scatter; and the noisy ellipses are recovered."""
    rng = np.random.default_rng(11)
    sets = [_ellipse((rng.normal(), rng.normal()), rng.uniform(0.5, 3), rng.uniform(0.1, 0.5), rng.uniform(-3, 3),
                     rng.uniform(0, 2 * np.pi, rng.integers(5, 60))) + rng.normal(scale=0.01, size=(1, 2))
            for _ in range(40)]
    sets += [rng.normal(size=(3, 2)), np.zeros((0, 2)), rng.normal(size=(4, 2)),
             np.column_stack([np.arange(8.0), 2 * np.arange(8.0)]),  # collinear
             np.vstack([_ellipse((0, 0), 2, 1, 0, np.linspace(0, 6, 9)), [[np.nan, 0.0]]]),
             np.ones((7, 2)),  # all coincident
             np.column_stack([np.r_[-3:3:12j], np.r_[-3:3:12j] ** 3]),  # no ellipse fits well
             rng.normal(size=(30, 2)) * [5.0, 0.01]]
    starts = np.r_[0, np.cumsum([len(s) for s in sets])]
    centers, axes, angles = fit_ellipses(np.vstack(sets), starts)
    for i, pts in enumerate(sets):
        one = fit_ellipse(pts)
        if one is None:
            assert np.all(np.isnan(centers[i])) and np.all(np.isnan(axes[i])) and np.isnan(angles[i]), i
        else:
            assert np.array_equal(centers[i], one[0]) and np.array_equal(axes[i], one[1]) and angles[i] == one[2]
    assert np.isfinite(centers[:40]).all() and np.isnan(centers[40:46]).all()


def test_batched_fit_of_a_large_set_equals_the_single_fit():
    """A cross-section of a million-point cloud holds thousands of points: the same bits alone or
    beside small sets."""
    rng = np.random.default_rng(2)
    big = _ellipse((1.0, -2.0), 0.3, 0.2, 0.4, rng.uniform(0, 2 * np.pi, 30000)) + rng.normal(scale=1e-3, size=(30000, 2))
    small = _ellipse((0.0, 0.0), 2.0, 1.0, 0.0, np.linspace(0, 6, 7))
    centers, axes, angles = fit_ellipses(np.vstack([small, big, small]), np.array([0, 7, 30007, 30014]))
    one = fit_ellipse(big)
    assert np.array_equal(centers[1], one[0]) and np.array_equal(axes[1], one[1]) and angles[1] == one[2]
    np.testing.assert_allclose(one[0], [1.0, -2.0], atol=1e-4)
    np.testing.assert_allclose(one[1], [0.3, 0.2], rtol=1e-3)
    assert np.array_equal(centers[0], centers[2])


def _rows_sums(pts):
    """The per-set sums as the (n, 2) rows code computes them: mean(axis=0), einsum, column_stack."""
    origin = pts.mean(axis=0)
    centred = pts - origin
    scale = float(np.sqrt(np.mean(np.einsum("ij,ij->i", centred, centred))))
    x, y = (centred / scale).T
    d = np.column_stack([x * x, x * y, y * y, x, y, np.ones_like(x)])
    return origin, scale, d.T @ d


def test_column_sums_equal_the_rows_code_bit_for_bit():
    """ellipse_sums (contiguous columns, a running-sum centroid, one design buffer) gives the bits of the
    rows code it replaces, for sets of 5 to 20,000 points with repeats and -0.0, at scales 1e-3 to 1e3;
    sums of batches joined solve as one batch."""
    from skelcore.metrics.ellipse_fit import EllipseSums, ellipse_sums, ellipses_from_sums

    rng = np.random.default_rng(4)
    sets = []
    for n in (5, 6, 8, 9, 17, 128, 129, 700, 4097, 20000):
        pts = _ellipse(rng.normal(size=2) * 10, rng.uniform(0.5, 3), rng.uniform(0.1, 0.5), rng.uniform(-3, 3),
                       rng.uniform(0, 2 * np.pi, n)) * 10.0 ** rng.integers(-3, 4)
        pts[::5] = np.round(pts[::5], 1)
        pts[1::7, 0] = -0.0
        sets.append(pts)
    starts = np.r_[0, np.cumsum([len(s) for s in sets])]
    xy = np.vstack(sets)
    sums = ellipse_sums(xy[:, 0].copy(), xy[:, 1].copy(), starts)
    assert sums.use.tolist() == list(range(len(sets)))
    for i, pts in enumerate(sets):
        origin, scale, sc = _rows_sums(pts)
        assert sums.origin[i].tobytes() == origin.tobytes() and sums.scale[i] == scale
        assert sums.sc[i].tobytes() == sc.tobytes(), i
    halves = [ellipse_sums(xy[:, 0].copy(), xy[:, 1].copy(), starts[:6]),
              ellipse_sums(xy[starts[5]:, 0].copy(), xy[starts[5]:, 1].copy(), starts[5:] - starts[5]).shifted(5)]
    joined = ellipses_from_sums(EllipseSums.joined(halves[::-1]), len(sets))
    assert all(np.array_equal(a, b, equal_nan=True) for a, b in zip(joined, fit_ellipses(xy, starts)))


def test_the_conditioning_bound_answers_as_the_svd():
    """``_conditioned`` (a trace^3 / det bound, the SVD where it cannot decide) gives ``np.linalg.cond(s3) <=
    1e12`` for scatter matrices of [x, y, 1] of unit-RMS sets from round to collinear (cond from 1 to past
    1e20, many near the cutoff), equal points and a zero matrix (non-finite sets never get this far)."""
    from skelcore.metrics.ellipse_fit import _conditioned

    rng = np.random.default_rng(11)
    mats = []
    for width in 10.0 ** np.linspace(-12, 0, 300):
        t = rng.uniform(-1, 1, int(rng.integers(5, 400)))
        xy = np.column_stack([t, width * rng.normal(size=len(t))]) @ np.linalg.qr(rng.normal(size=(2, 2)))[0]
        xy = (xy - xy.mean(0)) / np.sqrt(np.mean(np.sum((xy - xy.mean(0)) ** 2, axis=1)))
        d = np.column_stack([xy, np.ones(len(xy))])
        mats.append(d.T @ d)
    d = np.column_stack([np.zeros((6, 2)), np.ones(6)])
    mats += [d.T @ d, np.zeros((3, 3)), np.eye(3)]
    s3 = np.array(mats)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        cond = np.linalg.cond(s3)
        want = cond <= 1e12
    assert _conditioned(s3).tolist() == want.tolist()
    assert want.sum() > 100 and (~want).sum() > 50 and ((cond > 1e9) & (cond < 1e15)).sum() > 20
