"""Centeredness of skeletal points and curve samples (docs/metrics.md 3) and its analytic checks (docs/metrics.md 5.6)."""

from __future__ import annotations

import numpy as np
import pytest

from skelcore.curve import CurveSkeleton
from skelcore.metrics.curve_sampling import sample_curve
from skelcore.metrics.centeredness import (
    cross_section_centeredness,
    curve_centeredness,
    ring_length,
    skeletal_centeredness,
)
from skelcore.metrics.ellipse_fit import fit_ellipse
from skelcore.params import Params, k_center_for
from skelcore.shapes import cylinder, torus, y_shape

RADIUS = 0.5
LENGTH = 4.0


@pytest.fixture(scope="module")
def dense_cylinder():
    return cylinder(20000, radius=RADIUS, length=LENGTH, capped=True, seed=1)


def _axis_samples(shape, shift=(0.0, 0.0, 0.0)):
    curve = CurveSkeleton.from_raw(shape.curve_vertices + np.asarray(shift), shape.curve_edges)
    return sample_curve(curve, 200)


def _away_from_caps(points):
    return (points[:, 2] > 0.3) & (points[:, 2] < LENGTH - 0.3)


# ---------------------------------------------------------------- skeletal point set


def _skeletal_reference(cloud, skel, k):
    """Plain loops over the definition in docs/metrics.md 3, neighbours by brute-force sorting."""
    out = []
    for q in skel:
        d = np.sqrt(((skel - q) ** 2).sum(axis=1))
        nb = np.argsort(d, kind="stable")[:k]
        m_s = sum(skel[j] for j in nb) / k
        m_o = sum(cloud[j] for j in nb) / k
        big_m = sum(np.linalg.norm(cloud[j] - m_s) for j in nb) / k
        out.append(np.nan if big_m == 0 else max(0.0, 1 - np.linalg.norm(m_o - m_s) / big_m))
    return np.array(out)


@pytest.mark.parametrize("n, k_center", [(300, None), (257, 7), (40, 60)])
def test_skeletal_matches_plain_loop_reference(rng, n, k_center):
    cloud = rng.normal(size=(n, 3))
    skel = 0.3 * cloud + rng.normal(scale=0.2, size=(n, 3))
    params = Params(k_center=k_center)
    got = skeletal_centeredness(cloud, skel, params=params)
    want = _skeletal_reference(cloud, skel, min(k_center_for(n, params), n))
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)


@pytest.mark.parametrize("k_center", [10, 30])
def test_skeletal_coincident_points_break_ties_by_index_like_reference(rng, k_center):
    # contraction leaves clusters of exactly coincident points, some larger than k, some smaller:
    # ties both at distance 0 and at the boundary inside a neighbouring cluster
    centres = rng.normal(size=(25, 3))
    skel = centres[rng.integers(0, 25, size=400)]
    cloud = skel + rng.normal(scale=0.3, size=skel.shape)
    params = Params(k_center=k_center)
    got = skeletal_centeredness(cloud, skel, params=params)
    want = _skeletal_reference(cloud, skel, k_center)
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)


def test_skeletal_cluster_larger_than_k_uses_lowest_index_members():
    # 12 coincident skeletal points, k = 10: every member's neighbours are rows 0..9
    cloud = np.vstack([np.tile([1.0, 0, 0], (10, 1)), np.tile([-1.0, 0, 0], (2, 1))])
    c = skeletal_centeredness(cloud, np.zeros((12, 3)), params=Params(k_center=10))
    np.testing.assert_allclose(c, 0.0, atol=1e-12)  # all ten chosen cloud points lie on one side


def test_skeletal_negative_zero_coincides_with_zero():
    skel = np.zeros((12, 3))
    skel[::2, 0] = -0.0
    cloud = np.vstack([np.tile([1.0, 0, 0], (10, 1)), np.tile([-1.0, 0, 0], (2, 1))])
    c = skeletal_centeredness(cloud, skel, params=Params(k_center=10))
    np.testing.assert_allclose(c, 0.0, atol=1e-12)


def test_skeletal_rejects_non_finite_points():
    skel = np.zeros((12, 3))
    skel[3, 1] = np.nan
    with pytest.raises(ValueError):
        skeletal_centeredness(np.zeros((12, 3)), skel)


def test_skeletal_chunks_agree_with_one_pass(rng, monkeypatch):
    import skelcore.metrics.centeredness as mod

    cloud = rng.normal(size=(1000, 3))
    skel = 0.5 * cloud
    whole = skeletal_centeredness(cloud, skel)
    monkeypatch.setattr(mod, "_SKELETAL_CHUNK", 97)
    np.testing.assert_array_equal(skeletal_centeredness(cloud, skel), whole)


def test_skeletal_symmetric_ring_is_perfectly_centred():
    angles = np.linspace(0, 2 * np.pi, 16, endpoint=False)
    ring = np.column_stack([np.cos(angles), np.sin(angles), np.zeros(16)])
    c = skeletal_centeredness(ring, np.zeros((16, 3)), params=Params(k_center=16))
    np.testing.assert_allclose(c, 1.0, atol=1e-12)


def test_skeletal_one_sided_neighbourhood_scores_zero():
    # cloud points all on one side of their skeletal centroid at the same distance: |m_o-m_s| = M
    cloud = np.tile([1.0, 0.0, 0.0], (12, 1))
    c = skeletal_centeredness(cloud, np.zeros((12, 3)), params=Params(k_center=12))
    np.testing.assert_allclose(c, 0.0, atol=1e-12)


def test_skeletal_zero_spread_is_nan():
    pts = np.zeros((15, 3))
    assert np.all(np.isnan(skeletal_centeredness(pts, pts)))


def test_skeletal_zero_spread_only_where_it_occurs():
    # a far-away cluster where cloud == skeleton (M = 0) next to a healthy one
    ring = np.array([[np.cos(a), np.sin(a), 0.0] for a in np.linspace(0, 2 * np.pi, 10, endpoint=False)])
    cloud = np.vstack([ring, np.full((10, 3), 100.0)])
    skel = np.vstack([np.zeros((10, 3)), np.full((10, 3), 100.0)])
    c = skeletal_centeredness(cloud, skel, params=Params(k_center=10))
    np.testing.assert_allclose(c[:10], 1.0, atol=1e-12)
    assert np.all(np.isnan(c[10:]))


def test_skeletal_empty_input_gives_empty_output():
    assert skeletal_centeredness(np.empty((0, 3)), np.empty((0, 3))).shape == (0,)


def test_skeletal_rejects_mismatched_rows():
    with pytest.raises(ValueError):
        skeletal_centeredness(np.zeros((5, 3)), np.zeros((6, 3)))


def test_skeletal_cylinder_about_85_percent_pass(dense_cylinder):
    """docs/metrics.md 5.6: with k = 30 random ring points |m_o - m_s| / M is about 0.16; ~85% pass 0.75."""
    shape = cylinder(20000, radius=RADIUS, length=LENGTH, capped=False, seed=2)
    c = skeletal_centeredness(shape.cloud, shape.skeletal, params=Params(k_center=30))
    assert np.all(np.isfinite(c))
    passing = float(np.mean(c > 0.75))
    assert 0.78 < passing < 0.92
    assert 0.78 < float(np.median(c)) < 0.9


def test_skeletal_points_pushed_to_one_side_score_low():
    shape = cylinder(6000, radius=RADIUS, length=LENGTH, capped=False, seed=3)
    skel = shape.skeletal + [0.8 * RADIUS, 0.0, 0.0]
    c = skeletal_centeredness(shape.cloud, skel, params=Params(k_center=30))
    assert float(np.mean(c > 0.75)) < 0.05


# ---------------------------------------------------------------- curve skeleton


def _curve_reference(cloud, points, directions, params):
    """Straight from docs/metrics.md 3: every cloud point tested per sample, loops, fit_ellipse or fallback."""
    alpha = params.slab_factor * np.linalg.norm(cloud.max(0) - cloud.min(0))
    out = []
    for p, u in zip(points, directions):
        if not np.all(np.isfinite(u)):
            out.append(np.nan)
            continue
        u = u / np.linalg.norm(u)
        a = np.array([1.0, 0, 0]) if abs(u[0]) < 0.9 else np.array([0, 1.0, 0])
        g = np.cross(u, a)
        g /= np.linalg.norm(g)
        h = np.cross(u, g)
        slab = [x for x in cloud if abs(u @ (x - p)) < alpha / 2]
        p_hat = np.array([p @ g, p @ h])

        def dist(q):
            return np.linalg.norm(np.subtract(q, p_hat))

        flat = sorted(([x @ g, x @ h] for x in slab), key=dist)
        ring = flat[:1]
        for q in flat[1:]:
            if dist(q) < params.ring_growth * dist(ring[-1]):
                ring.append(q)
            else:
                break
        ring = np.array(ring)
        if len(ring) < 3:
            out.append(np.nan)
            continue
        fit = fit_ellipse(ring) if len(ring) >= 5 else None
        if fit is not None:
            centre, r = fit[0], fit[1].mean()
        else:
            centre, r = ring.mean(0), np.linalg.norm(ring - p_hat, axis=1).max()
        out.append(max(0.0, 1 - np.linalg.norm(p_hat - centre) / r))
    return np.array(out)


@pytest.mark.parametrize("slab_factor", [0.02, 0.06, 0.003])
def test_curve_matches_whole_cloud_reference_on_branching_shape(slab_factor):
    # 0.003 makes the grid cell (diagonal / 256) wider than the slab
    shape = y_shape(1500 if slab_factor > 0.01 else 6000, seed=4)
    rng = np.random.default_rng(5)
    samples = sample_curve(CurveSkeleton.from_raw(shape.curve_vertices, shape.curve_edges), 40)
    points = samples.points + rng.normal(scale=0.05, size=samples.points.shape)
    dirs = samples.directions + rng.normal(scale=0.2, size=samples.directions.shape)
    params = Params(slab_factor=slab_factor)
    got = curve_centeredness(shape.cloud, points, dirs, params=params)
    want = _curve_reference(shape.cloud, points, dirs, params)
    assert np.isfinite(want).sum() >= 10
    np.testing.assert_array_equal(np.isnan(got), np.isnan(want))
    np.testing.assert_allclose(got, want, atol=1e-9)


def test_curve_centred_axis_scores_one(dense_cylinder):
    """docs/metrics.md 5.6: the axis of a dense closed cylinder is perfectly centred away from the caps."""
    s = _axis_samples(dense_cylinder)
    c = curve_centeredness(dense_cylinder.cloud, s.points, s.directions)
    mid = _away_from_caps(s.points)
    assert mid.sum() > 150
    np.testing.assert_allclose(c[mid], 1.0, atol=1e-6)


@pytest.mark.parametrize("fraction", [0.1, 0.3, 0.5])
def test_curve_shifted_sideways_scores_one_minus_d_over_r(dense_cylinder, fraction):
    """docs/metrics.md 5.6: the axis shifted sideways by d scores about 1 - d / r."""
    d = fraction * RADIUS
    s = _axis_samples(dense_cylinder, shift=(d / np.sqrt(2), d / np.sqrt(2), 0.0))
    c = curve_centeredness(dense_cylinder.cloud, s.points, s.directions)
    mid = _away_from_caps(s.points)
    np.testing.assert_allclose(c[mid], 1 - fraction, atol=1e-3)


def test_curve_on_noisy_cylinder_is_close_to_one_minus_d_over_r():
    shape = cylinder(20000, radius=RADIUS, length=LENGTH, capped=True, seed=6)
    cloud = shape.cloud + np.random.default_rng(6).normal(scale=0.01 * RADIUS, size=shape.cloud.shape)
    s = _axis_samples(shape, shift=(0.2 * RADIUS, 0.0, 0.0))
    c = curve_centeredness(cloud, s.points, s.directions)
    mid = _away_from_caps(s.points)
    assert abs(np.median(c[mid]) - 0.8) < 0.02


def test_curve_scale_invariant(dense_cylinder):
    s = _axis_samples(dense_cylinder, shift=(0.1, 0.0, 0.0))
    c1 = curve_centeredness(dense_cylinder.cloud, s.points, s.directions)
    c2 = curve_centeredness(3.0 * dense_cylinder.cloud, 3.0 * s.points, s.directions)
    np.testing.assert_allclose(c1, c2, atol=1e-9)


def test_curve_direction_sign_does_not_matter(dense_cylinder):
    s = _axis_samples(dense_cylinder, shift=(0.1, 0.0, 0.0))
    c1 = curve_centeredness(dense_cylinder.cloud, s.points, s.directions)
    c2 = curve_centeredness(dense_cylinder.cloud, s.points, -s.directions)
    np.testing.assert_allclose(c1, c2, atol=1e-9)


def test_curve_torus_core_circle_is_centred():
    shape = torus(20000, R=1.0, r=0.3, n_curve=32, seed=7)
    s = sample_curve(CurveSkeleton.from_raw(shape.curve_vertices, shape.curve_edges), 100)
    c = curve_centeredness(shape.cloud, s.points, s.directions)
    # the polygon's chords sit slightly inside the circle; slabs of a curved tube are not circles
    assert np.all(np.isfinite(c))
    assert np.median(c) > 0.9


def test_curve_ring_isolation_ignores_a_parallel_branch():
    # two parallel cylinders; the slab of one axis cuts both, the ring must keep only the nearer
    a = cylinder(8000, radius=RADIUS, length=LENGTH, capped=False, seed=8)
    b_cloud = a.cloud + [3.0, 0.0, 0.0]
    cloud = np.vstack([a.cloud, b_cloud])
    s = _axis_samples(a, shift=(0.1, 0.0, 0.0))
    c = curve_centeredness(cloud, s.points, s.directions)
    mid = _away_from_caps(s.points)
    np.testing.assert_allclose(c[mid], 1 - 0.1 / RADIUS, atol=1e-3)


def test_curve_nan_direction_gives_nan(dense_cylinder):
    s = _axis_samples(dense_cylinder)
    dirs = s.directions.copy()
    dirs[5] = np.nan
    c = curve_centeredness(dense_cylinder.cloud, s.points, dirs)
    assert np.isnan(c[5])
    assert np.isfinite(c[4]) and np.isfinite(c[6])


def test_curve_fewer_than_three_ring_points_is_nan():
    cloud = np.array([[1.0, 0, 0], [-1.0, 0, 0], [0, 0, 5.0], [0, 0, -5.0]])
    c = curve_centeredness(cloud, np.zeros((1, 3)), np.array([[0, 0, 1.0]]))
    assert np.isnan(c[0])


def test_curve_three_ring_points_use_mean_and_max_distance():
    # 3 ring points: no ellipse; centre = their mean, r = largest distance from p_hat
    cloud = np.array([[1.0, 0, 0], [0, 1.0, 0], [-1.0, 0, 0], [0, 0, 10.0]])
    p = np.array([[0.0, -0.5, 0.0]])
    c = curve_centeredness(cloud, p, np.array([[0, 0, 1.0]]))
    centre = np.array([0.0, 1 / 3])
    r = 1.5  # distance from p_hat to (0, 1)
    np.testing.assert_allclose(c[0], max(0.0, 1 - np.linalg.norm(centre - [0, -0.5]) / r))


def test_curve_empty_slab_is_nan():
    cloud = np.array([[0, 0, 0.0], [0, 0, 1.0], [1, 1, 2.0]])
    c = curve_centeredness(cloud, np.array([[0, 0, 10.0]]), np.array([[0, 0, 1.0]]))
    assert np.isnan(c[0])


def test_curve_no_samples_gives_empty_output(dense_cylinder):
    c = curve_centeredness(dense_cylinder.cloud, np.empty((0, 3)), np.empty((0, 3)))
    assert c.shape == (0,)


def test_checkpoint_reaches_one_and_can_cancel(dense_cylinder):
    from skelcore.errors import Cancelled

    s = _axis_samples(dense_cylinder)
    seen: list[float] = []
    curve_centeredness(dense_cylinder.cloud, s.points, s.directions, checkpoint=seen.append)
    assert seen[-1] == 1.0 and seen == sorted(seen)

    def cancel(fraction: float) -> None:
        if fraction > 0.2:
            raise Cancelled()

    with pytest.raises(Cancelled):
        curve_centeredness(dense_cylinder.cloud, s.points, s.directions, checkpoint=cancel)
    with pytest.raises(Cancelled):
        skeletal_centeredness(dense_cylinder.cloud, dense_cylinder.skeletal, checkpoint=cancel)


# ---------------------------------------------------------------- helpers


def test_ring_length_stops_at_first_big_jump():
    assert ring_length(np.array([1.0, 1.2, 1.7, 2.5, 3.9, 4.0]), 1.5) == 4
    assert ring_length(np.array([1.0, 1.1]), 1.5) == 2
    assert ring_length(np.array([]), 1.5) == 0
    assert ring_length(np.array([0.0, 0.0, 1.0]), 1.5) == 1  # 0 < 1.5 x 0 is false


def test_cross_section_uses_ellipse_centre_and_mean_semi_axis():
    t = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    ring = np.column_stack([0.3 + 2.0 * np.cos(t), 1.0 * np.sin(t)])
    np.testing.assert_allclose(cross_section_centeredness(ring), 1 - 0.3 / 1.5)


def test_cross_section_clamps_at_zero():
    t = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    ring = np.column_stack([5 + np.cos(t), np.sin(t)])
    assert cross_section_centeredness(ring) == 0.0


def test_curve_grid_lookup_matches_reference_on_real_scan(scans):
    from plyfile import PlyData

    from skelcore.geometry import Normalization

    vertex = PlyData.read(str(scans / "hammer_4096.ply"))["vertex"]
    raw = np.column_stack([vertex["x"], vertex["y"], vertex["z"]]).astype(float)
    cloud = Normalization.from_cloud(raw).apply(raw)
    rng = np.random.default_rng(9)
    points = cloud[rng.choice(len(cloud), 15, replace=False)] * 0.8  # pulled inwards
    dirs = rng.normal(size=(15, 3))
    params = Params()
    got = curve_centeredness(cloud, points, dirs, params=params)
    want = _curve_reference(cloud, points, dirs, params)
    np.testing.assert_array_equal(np.isnan(got), np.isnan(want))
    np.testing.assert_allclose(got, want, atol=1e-9)


def test_the_neighbour_sums_are_numpys_bit_for_bit(rng):
    """The compiled m_s, m_o and M of skeletal centeredness (docs/performance.md 6.4) are the bits of the
    array code they replace: sums of gathered rows in order (m_s from its first row, m_o by numpy's
    reduce), einsum's squared lengths and numpy's pairwise mean, for
    k below, at and above numpy's blocks of 8 and 128, at scales 1e-3 to 1e3 and with -0.0 and repeats."""
    from skelcore.metrics.centeredness import _neighbour_sums

    for k in (1, 2, 7, 8, 9, 10, 30, 41, 129, 300):
        scale = 10.0 ** rng.integers(-3, 4, size=(600, 1))
        values = np.round(rng.normal(size=(600, 3)) * scale, 2)
        values[::7] = -0.0
        cloud = values + rng.normal(size=values.shape) * scale
        slot = rng.integers(0, 600, size=(300, k))
        m_s, m_o, spread = _neighbour_sums(values, cloud, slot)
        total = values[slot[:, 0]].copy()  # the rows summed in order from the first, then divided
        for j in range(1, k):
            total += values[slot[:, j]]
        d = cloud[slot] - (total / k)[:, None, :]
        assert m_s.tobytes() == (total / k).tobytes()
        assert m_o.tobytes() == (np.add.reduce(cloud[slot], axis=1) / k).tobytes()
        assert spread.tobytes() == np.sqrt(np.einsum("ijk,ijk->ij", d, d)).mean(axis=1).tobytes()
    with pytest.raises(ValueError, match="neighbour_sums"):
        _neighbour_sums(values, cloud, np.full((3, 2), 600))


@pytest.mark.parametrize("rounds, first", [(1, 0.5), (3, 0.1), (1, 4.0)])
def test_curve_ball_rings_equal_whole_slab_rings(monkeypatch, scans, rounds, first):
    """Rings found in balls around p (docs/performance.md 6.5) are the whole slab's rings, bit for bit,
    NaNs included, on both paths: an integer lattice (exact distance ties, rings cut inside a tie run),
    the hammer scan, a branching shape and a torus, with random and axis directions."""
    from plyfile import PlyData

    from skelcore.geometry import Normalization
    from skelcore.metrics import centeredness

    rng = np.random.default_rng(11)
    side = [(x, y) for x in range(-4, 5) for y in range(-4, 5) if max(abs(x), abs(y)) == 4]
    lattice = np.array([(x, y, z) for z in range(20) for x, y in side], dtype=float)
    vertex = PlyData.read(str(scans / "hammer_4096.ply"))["vertex"]
    raw = np.column_stack([vertex["x"], vertex["y"], vertex["z"]]).astype(float)
    hammer = Normalization.from_cloud(raw).apply(raw)
    branch, ring = y_shape(4000, seed=2).cloud, torus(4000, 1.0, 0.3, seed=3).cloud
    cases = [  # (cloud, points, directions, slab factor): a thick slab holds the lattice's rings in the first balls
        (lattice * 0.1, np.column_stack([rng.integers(-2, 3, (40, 2)), rng.integers(1, 19, 40)]) * 0.1,
         np.tile([0.0, 0, 1], (40, 1)), 0.3),  # ties whose order changes the fit's sums
        (lattice, np.column_stack([rng.integers(-2, 3, (40, 2)), rng.integers(1, 19, 40)]), np.tile([0.0, 0, 1], (40, 1)), 0.05),
        (lattice, np.column_stack([rng.integers(-2, 3, (40, 2)), rng.integers(1, 19, 40)]), rng.normal(size=(40, 3)) * [0.1, 0.1, 1], 0.05),
        (hammer, hammer[rng.choice(len(hammer), 40)] * 0.8, rng.normal(size=(40, 3)), 0.05),
        (branch, branch[rng.choice(len(branch), 40)] * 0.5, rng.normal(size=(40, 3)), 0.05),
        (ring, ring[rng.choice(len(ring), 40)] * 0.9, rng.normal(size=(40, 3)), 0.05),
    ]
    for cloud, pts, dirs, slab in cases:
        dirs[3] = np.nan
        monkeypatch.setattr(centeredness, "_BALL_ROUNDS", 0)  # every ring from its whole slab
        want = centeredness.curve_centeredness(cloud, pts, dirs, params=Params(slab_factor=slab))
        monkeypatch.setattr(centeredness, "_BALL_ROUNDS", rounds)
        monkeypatch.setattr(centeredness, "_BALL_FIRST", first)
        for at_once in (0, 10**12):
            monkeypatch.setattr(centeredness, "_CURVE_AT_ONCE", at_once)
            got = centeredness.curve_centeredness(cloud, pts, dirs, params=Params(slab_factor=slab))
            assert np.array_equal(got, want, equal_nan=True)
        assert np.isfinite(want).sum() >= 10


def test_curve_rings_the_solver_rejects_on_both_paths(monkeypatch):
    """The large-cloud path fits its rings' sums after the spans (docs/performance.md 6.5); a ring the
    stacked solve rejects (collinear: a flat sheet cut across) takes its ring's mean and farthest point,
    found again, and rings of 3 or 4 points take them at once: both paths equal, bit for bit, and equal
    the whole-cloud reference."""
    from skelcore.metrics import centeredness

    rng = np.random.default_rng(8)
    sheet = np.column_stack([rng.uniform(0, 1, 1500), rng.uniform(0, 0.3, 1500), np.zeros(1500)])
    t = rng.uniform(0, 2 * np.pi, 600)
    tube = np.column_stack([rng.uniform(4, 5, 600), 0.1 * np.cos(t), 0.1 * np.sin(t)])
    three, four = ([[x, 0.01 * np.cos(a), 0.01 * np.sin(a)] for a in np.arange(k) * 2 * np.pi / k] for x, k in ((2.0, 3), (3.0, 4)))
    cloud = np.vstack([sheet, tube, three, four])
    above = np.column_stack([rng.uniform(0.2, 0.8, 12), rng.uniform(0.1, 0.2, 12), np.full(12, 0.1)])  # rings: lines
    points = np.vstack([above, [[2.0, 0.001, 0.0], [3.0, 0.001, 0.0]], [[4.5, 0.01, 0.0], [4.2, 0.0, 0.0]]])
    dirs = np.tile([1.0, 0.0, 0.0], (len(points), 1))
    params = Params()
    want = _curve_reference(cloud, points, dirs, params)
    outs = []
    for at_once in (10**12, 0):
        monkeypatch.setattr(centeredness, "_CURVE_AT_ONCE", at_once)
        outs.append(curve_centeredness(cloud, points, dirs, params=params))
    assert np.array_equal(outs[0], outs[1], equal_nan=True)
    np.testing.assert_array_equal(np.isnan(outs[1]), np.isnan(want))
    np.testing.assert_allclose(outs[1], want, atol=1e-9)
    assert np.isfinite(want).all()
