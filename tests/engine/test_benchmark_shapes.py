"""The benchmark's shapes: exact skeletons (graph counts, inside their shapes), surface samples on
the exact surface and uniform, the canal conditions enforced (skelcore.benchmark)."""

from __future__ import annotations

import numpy as np
import pytest

import skelcore
from skelcore.benchmark import SurfaceSampler, make_shape, reference_skeleton, signed_distance
from skelcore.benchmark.suite import SHAPES
from skelcore.benchmark.tubes import BenchShape, GeometryError, Tube, check_geometry


def _shape(name: str, seed: int = 0) -> BenchShape:
    entry = SHAPES[name]
    return make_shape(name, entry.family, np.random.SeedSequence(entry.seed(seed)), **entry.params)


def _counts(v, e):
    deg = np.bincount(e.ravel(), minlength=len(v))
    return int(np.sum(deg >= 3)), int(np.sum(deg == 1)), int(len(e) - len(v) + 1)


@pytest.mark.parametrize("name, junctions, endpoints, cycles", [
    ("tube_a", 0, 2, 0), ("elliptic", 0, 2, 0), ("junction_y", 1, 3, 0), ("junction_t", 1, 3, 0),
    ("junction_x", 1, 4, 0), ("tree_2", 1, None, 0), ("torus", 0, 0, 1), ("genus2", 2, 0, 2),
    ("hand", 1, 6, 0), ("plate", 0, 0, 1),
])
def test_reference_skeleton_has_the_shapes_topology(name, junctions, endpoints, cycles):
    v, e, r = reference_skeleton(_shape(name))
    j, ends, c = _counts(v, e)
    assert (j, c) == (junctions, cycles)
    if endpoints is not None:
        assert ends == endpoints
    assert np.all(r > 0) and len(r) == len(v)


@pytest.mark.parametrize("levels", [2, 3, 4])
def test_trees_have_the_requested_levels(levels):
    shape = make_shape(f"tree{levels}", "tree", 5, levels=levels)
    v, e, _ = reference_skeleton(shape)
    j, ends, c = _counts(v, e)
    # every fork has 2-3 children: leaves = tubes - junctions, a tree (no cycle), one root end
    assert c == 0 and j == len(shape.tubes) - (ends - 1)
    depth = {0: 1}
    for t in shape.tubes:  # tubes are made parent first
        depth[t.end] = depth[t.start] + 1
    assert max(depth.values()) == levels + 1


def test_junction_radius_is_the_thickest_tube_at_the_node():
    shape = _shape("junction_y")
    v, e, r = reference_skeleton(shape)
    assert r[0] == pytest.approx(0.30)  # node 0: arms of 0.30, 0.20 and 0.12 meet there
    assert np.allclose(v[0], 0.0)


@pytest.mark.parametrize("name", sorted(SHAPES))
def test_surface_samples_lie_on_the_exact_surface(name):
    shape = _shape(name)
    s = SurfaceSampler(shape).sample(3000, np.random.default_rng(2))
    assert s.points.shape == (3000, 3)
    sd = signed_distance(shape, s.points) / s.radius
    # the sampler drops points inside balls 0.1 radii apart: within 0.1^2 / 8 of the union
    assert np.max(np.abs(sd)) < 2e-3
    assert np.allclose(np.linalg.norm(s.normals, axis=1), 1.0)


@pytest.mark.parametrize("name", sorted(SHAPES))
def test_exact_skeleton_lies_inside_its_shape(name):
    """Boundedness (docs/metrics.md 2, rays) of the reference curve against a clean cloud of its shape is 1: it
    lies inside (tree_4's twigs, 0.03 thick, need more points to close their surface)."""
    shape = _shape(name)
    n = 8000 if name == "tree_4" else 2500
    cloud = SurfaceSampler(shape).sample(n, np.random.default_rng(3)).points
    v, e, _ = reference_skeleton(shape)
    ev = skelcore.evaluate(cloud, curve=(v, e))
    assert ev.summary()["boundedness"]["curve"] >= 0.98


def test_torus_samples_are_area_uniform():
    """On a ring of tube radius r around a circle of radius R the outer half (away from the axis) has
    area share 1/2 + r / (pi R): the sampler weights by the exact area element."""
    shape = make_shape("ring", "torus", 0, R=1.0, r=0.3, wobble=0.0)
    s = SurfaceSampler(shape).sample(120_000, np.random.default_rng(4))
    outer = np.mean(np.hypot(s.points[:, 0], s.points[:, 1]) > 1.0)
    assert outer == pytest.approx(0.5 + 0.3 / np.pi, abs=0.005)  # binomial spread 0.0014


def test_a_cone_like_tube_is_sampled_in_proportion_to_its_radius():
    """A straight tube whose radius grows linearly (r = 0.1 + 0.1 x): the points in a slab grow like
    the canal surface's area there, proportional to the mean radius (0.2 on [0.5, 1.5], 0.3 on
    [1.5, 2.5]; the envelope touches the ball at x at x - r r', which shifts both slabs alike)."""
    tube = Tube(np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0.0]]), np.array([0.1, 0.2, 0.3, 0.4]), start=0, end=1)
    shape = BenchShape("cone", "test", np.array([[0, 0, 0], [3, 0, 0.0]]), (tube,))
    sampler = SurfaceSampler(shape)
    s = sampler.sample(60_000, np.random.default_rng(5))
    body = (s.points[:, 0] > 0.5) & (s.points[:, 0] < 2.5)
    first, second = np.sum(body & (s.points[:, 0] < 1.5)), np.sum(body & (s.points[:, 0] >= 1.5))
    assert second / first == pytest.approx(0.3 / 0.2, rel=0.03)  # binomial spread: 0.9 %


def test_elliptic_tube_radius_is_its_minor_semi_axis():
    shape = _shape("elliptic")
    v, e, r = reference_skeleton(shape)
    tube = shape.tubes[0]
    assert tube.flatten < 1
    t = tube.vertex_parameters()  # the two end nodes come first, then the inner vertices
    assert np.allclose(r, tube.flatten * tube.radius(np.concatenate([[0.0, 1.0], t[1:-1]])))
    s = SurfaceSampler(shape).sample(4000, np.random.default_rng(6))
    d = np.linalg.norm(s.points[:, None, :] - v[None, ::5, :], axis=2).min(axis=1)
    # every surface point is at least the minor semi-axis from the centre curve (up to chords)
    assert np.min(d / s.radius) > 0.97


def test_plate_is_labelled_ill_posed_and_others_are_not():
    assert "ill-posed" in _shape("plate").ill_posed
    assert all(_shape(n).ill_posed is None for n in ("tube_a", "torus", "hand"))


def test_shapes_are_deterministic_from_their_seed():
    a, b, c = _shape("tree_3", 0), _shape("tree_3", 0), _shape("tree_3", 1)
    va, vb, vc = reference_skeleton(a)[0], reference_skeleton(b)[0], reference_skeleton(c)[0]
    assert np.array_equal(va, vb)
    assert va.shape != vc.shape or not np.allclose(va, vc)


def test_check_geometry_refuses_touching_and_too_tight_tubes():
    hairpin = Tube(np.array([[0, 0, 0], [2, 0, 0], [2, 0.3, 0], [0, 0.3, 0.0]]), np.full(4, 0.2), start=0, end=1)
    shape = BenchShape("hairpin", "test", np.array([[0, 0, 0], [0, 0.3, 0.0]]), (hairpin,))
    with pytest.raises(GeometryError):
        check_geometry(shape)
    steep = Tube(np.array([[0, 0, 0], [0.5, 0, 0], [1, 0, 0.0]]), np.array([0.1, 0.5, 0.9]), start=0, end=1)
    with pytest.raises(GeometryError, match="radius changes too fast"):
        check_geometry(BenchShape("steep", "test", np.array([[0, 0, 0], [1, 0, 0.0]]), (steep,)))
    far = Tube(np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0.0]]), np.full(3, 0.2), start=0, end=1)
    check_geometry(BenchShape("straight", "test", np.array([[0, 0, 0], [2, 0, 0.0]]), (far,)))
