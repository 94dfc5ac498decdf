"""The skeleton's cycles against the shape's tunnels (skelcore/diagnostics/cycles.py, interior.py)."""

from __future__ import annotations

import gudhi
import numpy as np
import pytest
from diagnostics_helpers import attach_path, normalized
from scipy import ndimage

from skelcore import Params, shapes
from skelcore.diagnostics import betti_numbers, find_cycle_defects, voxelize_interior
from skelcore.diagnostics.cycles import simplify_polygon, solid_angle_polygon
from skelcore.geometry import Normalization
from skelcore.metrics.boundedness import boundedness


def _rot(seed: int) -> np.ndarray:
    q, _ = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    return q


@pytest.mark.parametrize("seed", range(6))
def test_betti_numbers_match_gudhi_cubical_homology(seed):
    solid = np.random.default_rng(seed).random((10, 11, 9)) < 0.45
    cc = gudhi.CubicalComplex(top_dimensional_cells=np.where(np.pad(solid, 1), 0.0, 1.0))
    cc.compute_persistence()
    assert list(betti_numbers(solid)) == cc.persistent_betti_numbers(0.0, 0.0)[:3]


def test_solid_angle_of_a_circle_on_its_axis():
    a = np.linspace(0, 2 * np.pi, 400, endpoint=False)
    circle = np.column_stack([np.cos(a), np.sin(a), np.zeros_like(a)])
    z = np.array([0.1, 0.5, 2.0])
    p = np.column_stack([np.zeros(3), np.zeros(3), z])
    expect = 2 * np.pi * (1 - z / np.sqrt(z**2 + 1))
    got = np.mod(solid_angle_polygon(p, circle), 4 * np.pi)
    assert np.allclose(np.minimum(np.abs(got - expect), np.abs(got + expect - 4 * np.pi)), 0, atol=1e-3)


def test_simplified_polygon_stays_within_tolerance():
    a = np.linspace(0, 2 * np.pi, 500, endpoint=False)
    poly = np.column_stack([np.cos(a), np.sin(a), 0.1 * np.sin(3 * a)])
    simple = simplify_polygon(poly, 0.01)
    assert 10 < len(simple) < 100
    # every original vertex is within tol of the simplified closed polygon
    seg_a, seg_b = simple, np.roll(simple, -1, axis=0)
    ab = seg_b - seg_a
    t = np.clip(np.einsum("pij,ij->pi", poly[:, None] - seg_a, ab) / np.einsum("ij,ij->i", ab, ab), 0, 1)
    d = np.linalg.norm(poly[:, None] - (seg_a + t[..., None] * ab), axis=2).min(axis=1)
    assert d.max() <= 0.01 + 1e-12


def test_voxel_interior_agrees_with_boundedness():
    """The lattice rays classify like the boundedness of docs/metrics.md 2: the torus's tube inside, its hole and
    the space beside it outside."""
    s = shapes.torus(n=4000)
    norm = Normalization.from_cloud(s.cloud)
    c = norm.apply(s.cloud)
    vs = voxelize_interior(c)
    q = norm.apply(np.array([[1.0, 0, 0], [0, 0, 0], [0.0, 0.45, 0], [2.0, 0, 0], [0.0, -1.0, 0.1]]))
    ijk = vs.index_of(q)
    inside = vs.inside[ijk[:, 0], ijk[:, 1], ijk[:, 2]]
    beta = boundedness(c, q)
    assert inside.tolist() == (beta > 0.75).tolist() == [True, False, False, False, True]


@pytest.mark.parametrize("make, tunnels", [(shapes.torus, 1), (shapes.genus2, 2), (shapes.t_shape, 0),
                                           (shapes.tree3, 0), (shapes.cylinder, 0)])
@pytest.mark.parametrize("n, noise", [(1000, 0.0), (4000, 0.05)])
def test_true_skeleton_has_no_cycle_defect(make, tunnels, n, noise):
    s = make(n=n, seed=1)
    if noise:
        s = shapes.with_noise(s, noise, seed=1)
    c, curve, samples, _ = normalized(s.cloud, s.curve_vertices, s.curve_edges)
    r = find_cycle_defects(c, curve, samples=samples)
    assert r.shape_tunnels == tunnels == r.n_cycles == r.linked
    assert r.warnings() == [] and not r.vertex_flag.any() and not r.sample_flag.any()


def test_rotated_torus_core_is_legitimate():
    s = shapes.torus(n=3000, seed=2)
    q = _rot(2)
    c, curve, _, _ = normalized(s.cloud @ q.T, s.curve_vertices @ q.T, s.curve_edges)
    r = find_cycle_defects(c, curve)
    assert (r.n_cycles, r.shape_tunnels, r.linked, r.n_spurious, r.missing) == (1, 1, 1, 0, 0)
    assert r.cycle_linking.tolist() == [1]


@pytest.mark.parametrize("gap", [1, 4])
def test_torus_cut_open_misses_its_tunnel(gap):
    s = shapes.torus(n=3000, seed=3)
    c, curve, _, _ = normalized(s.cloud, s.curve_vertices, s.curve_edges[gap:])
    r = find_cycle_defects(c, curve)
    assert (r.n_cycles, r.shape_tunnels, r.missing) == (0, 1, 1)
    (w,) = r.warnings()
    assert w.code == "missing_cycles" and "1 missing" in w.message


def test_genus2_with_one_loop_cut_misses_one_tunnel():
    s = shapes.genus2(n=4000, seed=4)
    c, curve, _, _ = normalized(s.cloud, s.curve_vertices, s.curve_edges[3:])
    r = find_cycle_defects(c, curve)
    assert (r.n_cycles, r.shape_tunnels, r.linked, r.missing) == (1, 2, 1, 1)


def test_chord_inside_the_torus_tube_flags_the_small_loop_only():
    """A chord between two core vertices 3 apart, bowed inside the tube: the small loop it closes is
    spurious; the core circle (through the long arc) is not."""
    s = shapes.torus(n=4000, n_curve=32, seed=5)
    mid = (s.curve_vertices[0] + s.curve_vertices[3]) / 2 * 1.1  # 0.1 R outward, inside the tube
    v, e, ids = attach_path(s.curve_vertices, s.curve_edges, 0, mid, 2, to=None)
    v, e, _ = attach_path(v, e, int(ids[-1]), s.curve_vertices[3], 1, to=3)
    c, curve, samples, _ = normalized(s.cloud, v, e)
    r = find_cycle_defects(c, curve, samples=samples)
    assert (r.n_cycles, r.shape_tunnels, r.linked, r.n_spurious, r.missing) == (2, 1, 1, 1, 0)
    flagged = r.branch_spurious
    assert flagged[r.branches.vertex_branch[ids[0]]]  # the chord
    assert flagged[r.branches.vertex_branch[1]]  # the short arc 0-1-2-3
    assert not flagged[r.branches.vertex_branch[10]]  # the long arc
    assert r.vertex_flag[[1, 2]].all() and not r.vertex_flag[10:30].any()
    (w,) = r.warnings()
    assert w.code == "spurious_cycles"


def test_loop_inside_a_cylinder_is_spurious_and_a_shortcut_around_a_hole_is_not():
    s = shapes.cylinder(n=3000, seed=6)
    v, e, _ = attach_path(s.curve_vertices, s.curve_edges, 8, s.curve_vertices[10] + [0.2, 0, 0], 2, to=None)
    v, e, _ = attach_path(v, e, len(v) - 1, s.curve_vertices[12], 2, to=12)
    c, curve, _, _ = normalized(s.cloud, v, e)
    r = find_cycle_defects(c, curve)
    assert (r.n_cycles, r.n_spurious, r.missing) == (1, 1, 0)
    # a chord across the torus's hole (through the air) makes two cycles, both around tunnels:
    # no spurious cycle (the edge is outside's to flag)
    t = shapes.torus(n=3000, seed=6)
    v, e, _ = attach_path(t.curve_vertices, t.curve_edges, 0, t.curve_vertices[16], 6, to=16)
    c, curve, _, _ = normalized(t.cloud, v, e)
    r = find_cycle_defects(c, curve)
    assert (r.n_cycles, r.n_spurious, r.missing) == (2, 0, 0)


def test_tangle_of_loops_is_counted():
    """Five small loops hung along the T's bar: five spurious cycles."""
    s = shapes.t_shape(n=4000, seed=7)
    v, e = s.curve_vertices, s.curve_edges
    bar = np.flatnonzero(np.abs(v[:, 2]) < 1e-12)
    bar = bar[np.argsort(v[bar, 0])]
    for k in range(5):
        a, b = int(bar[2 + 3 * k]), int(bar[3 + 3 * k])
        v, e, ids = attach_path(v, e, a, (v[a] + v[b]) / 2 + [0, 0.1, 0.05], 1)
        v, e, _ = attach_path(v, e, int(ids[-1]), v[b], 1, to=b)
    c, curve, _, _ = normalized(s.cloud, v, e)
    r = find_cycle_defects(c, curve, params=Params(cycles_voxels=64))
    assert (r.n_cycles, r.shape_tunnels, r.n_spurious) == (5, 0, 5)
    assert r.to_dict()["spurious"] == 5 and r.grid[0] > 0


def test_interior_cavities_are_filled_and_counted():
    # a hollow ball of voxels: beta = (1, 0, 1)
    g = np.indices((15, 15, 15)) - 7
    r = np.sqrt((g**2).sum(axis=0))
    shell = (r < 6) & (r > 3)
    assert betti_numbers(shell) == (1, 0, 1)
    assert betti_numbers(ndimage.binary_fill_holes(shell)) == (1, 0, 0)


@pytest.mark.parametrize("seed", range(3))
def test_lattice_rays_match_a_walk_along_each_ray(seed):
    """The compiled sweeps that count the interior's lattice rays against walking every ray voxel by voxel."""
    from skelcore.diagnostics.interior import LATTICE_DIRECTIONS, lattice_hit_counts

    target = np.random.default_rng(seed).random((7, 9, 6)) < 0.08
    shape = np.array(target.shape)
    want = np.zeros(target.shape, np.uint8)
    for d in LATTICE_DIRECTIONS:
        for v in np.ndindex(*target.shape):
            p = np.array(v) + d
            while np.all(p >= 0) and np.all(p < shape):
                if target[tuple(p)]:
                    want[v] += 1
                    break
                p = p + d
    got = lattice_hit_counts(target)
    assert got.dtype == np.uint8 and 0 < got.max() <= 26
    np.testing.assert_array_equal(got, want)
    assert lattice_hit_counts(target[:, :, :1]).shape == (7, 9, 1)  # rows of one voxel


def test_fill_and_growth_are_scipys_and_a_filled_solid_has_no_cavity():
    """The labelling fill and the growth by one voxel give scipy's voxels, and the count that skips the
    cavities of a filled solid gives the full count, on random grids of every density."""
    from skelcore.diagnostics.interior import fill_holes, grow_by_one

    rng = np.random.default_rng(3)
    for shape in [(1, 1, 1), (1, 4, 4), (2, 2, 2), (5, 6, 7), (9, 1, 9), (12, 12, 12)]:
        for density in (0.0, 0.1, 0.3, 0.5, 0.7, 1.0):
            grid = rng.random(shape) < density
            filled = fill_holes(grid)
            np.testing.assert_array_equal(filled, ndimage.binary_fill_holes(grid))
            np.testing.assert_array_equal(grow_by_one(grid), ndimage.binary_dilation(grid, np.ones((3, 3, 3), bool)))
            assert betti_numbers(filled, filled=True) == betti_numbers(filled)
