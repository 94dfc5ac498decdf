"""The voxel adapters' shared pieces: a cloud's solid volume (the frame map with the half-voxel right,
the fill, the voxel size chosen to fit ``max_voxels``, the one-line refusals) and skeleton voxels as
a graph, checked against a brute-force statement of the triangle rule."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from skelcore import shapes
from skelcore.adapters.voxel_graph import voxel_edges
from skelcore.adapters.voxelize import default_voxel_size, fitting_voxel_size, grid_shape, voxelize_solid
from skelcore.errors import SkelInputError


def test_each_point_lies_in_the_voxel_whose_centre_maps_back_to_it():
    """Voxel i is centred on ``i * size + origin``: every point is within half a voxel of its voxel's
    centre, per coordinate, and its voxel is part of the solid."""
    cloud = shapes.cylinder(3000, seed=1).cloud + [3.0, -7.0, 0.25]
    grid = voxelize_solid(cloud)
    idx = grid.index_of(cloud)
    centres = grid.to_cloud_frame(idx)
    assert np.abs(cloud - centres).max() <= grid.size / 2 * (1 + 1e-9)
    assert grid.solid[tuple(idx.T)].all()
    assert idx.min() >= 1 and np.all(idx.max(axis=0) < np.array(grid.solid.shape) - 1)  # a background border


@pytest.mark.parametrize("make, volume", [
    (lambda: shapes.cylinder(4096, seed=0), np.pi * 0.5 ** 2 * 4.0),
    (lambda: shapes.torus(4096, seed=0), 2 * np.pi ** 2 * 1.0 * 0.3 ** 2),
])
def test_the_fill_recovers_the_solid(make, volume):
    """The filled voxels' volume is the shape's within 15 % (the shell adds about half a voxel)."""
    grid = voxelize_solid(make().cloud)
    assert grid.solid.sum() * grid.size ** 3 == pytest.approx(volume, rel=0.15)


def test_the_default_voxel_size_is_twice_the_median_spacing():
    cloud = np.array([[0, 0, 0], [1, 0, 0], [0, 3, 0], [0, 3, 0.5]], dtype=float)
    assert default_voxel_size(cloud) == pytest.approx(2 * 0.75)  # nearest distances 1, 1, 0.5, 0.5


def test_an_open_shell_and_a_huge_given_grid_are_one_line_refusals():
    cloud = shapes.cylinder(3000, seed=1).cloud
    with pytest.raises(SkelInputError, match=r"voxel shell does not close at voxel_size .* \(raise closing or voxel_size\)"):
        voxelize_solid(cloud, default_voxel_size(cloud) / 2, closing=0)
    with pytest.raises(SkelInputError, match=r"^voxel_size 0\.05 gives a \d+ x \d+ x \d+ grid \([\d,]+ voxels > "
                                             r"max_voxels 1,000\): give a larger voxel_size$"):
        voxelize_solid(cloud, 0.05, max_voxels=1000)
    with pytest.raises(SkelInputError, match=r"^max_voxels 500 is below the smallest grid with closing 2 \(729 voxels\)"):
        voxelize_solid(cloud, max_voxels=500)


def test_the_default_size_is_the_smallest_that_fits_max_voxels():
    """The spacing default when its grid fits; else raised just enough: the grid fits, a slightly
    smaller size would not, and the grid says where the size came from."""
    cloud = shapes.cylinder(3000, seed=1).cloud
    h0 = default_voxel_size(cloud)
    fine = voxelize_solid(cloud)
    assert (fine.size, fine.source) == (h0, "spacing")
    limit = fine.solid.size // 3
    grid = voxelize_solid(cloud, max_voxels=limit)
    box = cloud.min(axis=0), cloud.max(axis=0)
    assert grid.source == "max_voxels" and grid.size > h0 and grid.solid.size <= limit
    assert np.prod(grid_shape(*box, grid.size * (1 - 1e-9), 2)) > limit
    assert fitting_voxel_size(*box, grid.size, 2, limit) == grid.size
    assert fitting_voxel_size(*box, 2 * grid.size, 2, limit) == 2 * grid.size  # never below the floor given
    assert voxelize_solid(cloud, grid.size, max_voxels=limit).source == "given"
    assert grid.info() == {"voxel_size": grid.size, "voxel_size_source": "max_voxels",
                           "grid": list(grid.solid.shape), "voxels": int(grid.solid.sum())}


@pytest.mark.parametrize("kind", ["skimage", "kimimaro"])
def test_a_voxel_adapter_chooses_a_fitting_size_and_reports_it(kind):
    """A grid too large for ``max_voxels`` at the default size runs at the chosen size (in the
    result's info); the same limit with an explicit smaller size still refuses."""
    from skelcore.adapters import run

    pytest.importorskip("skimage" if kind == "skimage" else "kimimaro")
    cloud = shapes.cylinder(1500, seed=0).cloud
    limit = voxelize_solid(cloud).solid.size // 2
    res = run(kind, cloud, {"max_voxels": limit})
    info = res.info
    assert info["voxel_size_source"] == "max_voxels" and info["voxel_size"] > default_voxel_size(cloud)
    assert np.prod(info["grid"]) <= limit and res.curve.n_edges > 0
    with pytest.raises(SkelInputError, match=r"> max_voxels [\d,]+\): give a larger voxel_size$"):
        run(kind, cloud, {"max_voxels": limit, "voxel_size": default_voxel_size(cloud)})


def _brute_edges(vox: np.ndarray) -> set[tuple[int, int]]:
    """The docstring's rule, pair by pair: 26-neighbours joined unless a third skeleton voxel is
    strictly nearer to both ends than they are to each other."""
    out = set()
    for a, b in itertools.combinations(range(len(vox)), 2):
        d = np.abs(vox[a] - vox[b]).max()
        if d != 1:
            continue
        ab = np.sum((vox[a] - vox[b]) ** 2)
        ca = np.sum((vox - vox[a]) ** 2, axis=1)
        cb = np.sum((vox - vox[b]) ** 2, axis=1)
        if not np.any((ca < ab) & (cb < ab) & (np.abs(vox - vox[a]).max(axis=1) <= 1)
                      & (np.abs(vox - vox[b]).max(axis=1) <= 1)):
            out.add((a, b))
    return out


@pytest.mark.parametrize("seed", range(4))
def test_voxel_edges_match_the_triangle_rule_by_brute_force(seed):
    rng = np.random.default_rng(seed)
    vox = np.unique(rng.integers(0, 5, size=(40, 3)), axis=0)
    assert {tuple(e) for e in voxel_edges(vox).tolist()} == _brute_edges(vox)


def test_voxel_edges_of_lines_rings_and_a_square():
    diagonal = np.array([[i, i, i] for i in range(6)])
    assert voxel_edges(diagonal).tolist() == [[i, i + 1] for i in range(5)]
    stair = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [2, 1, 0], [2, 2, 0]])  # no short-cut triangles left
    assert len(voxel_edges(stair)) == len(stair) - 1
    angles = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    ring = np.unique(np.round(np.column_stack([8 * np.cos(angles), 8 * np.sin(angles), 0 * angles])).astype(int), axis=0)
    edges = voxel_edges(ring)
    assert len(edges) - len(ring) + 1 == 1  # the ring's one cycle, and only it
    square = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])
    assert len(voxel_edges(square)) == 4  # its diagonals are short-cut by the corners
