"""The tunnels that ``missing_cycles`` counts (skelcore.diagnostics.interior.firm_tunnels): stray points,
noise bridging two strands and a sparse half invent none; a tunnel that is there is still counted, so
a cycle cut open is still found (docs/diagnostics.md "Cycles", "Stray points, noise and sparse halves")."""

from __future__ import annotations

import numpy as np

from skelcore import Params
from skelcore.benchmark.neurons import MeshSampler, load_neuron
from skelcore.benchmark.surface_sampling import SurfaceSampler
from skelcore.benchmark.tubes import BenchShape, Tube, reference_skeleton
from skelcore.curve import CurveSkeleton
from skelcore.diagnostics import find_cycle_defects, voxelize_interior, wide_tunnels
from skelcore.diagnostics.interior import firm_tunnels, supported_voxels
from skelcore.geometry import Normalization
P = Params()


def _interior(cloud: np.ndarray):
    return voxelize_interior(cloud, voxels=P.cycles_voxels, min_spacing_factor=P.cycles_voxel_spacing,
                             inside_share=P.beta_star)


def _defects(cloud: np.ndarray, verts: np.ndarray, edges: np.ndarray):
    """(the interior, find_cycle_defects) of a raw cloud and curve, both normalized."""
    norm = Normalization.from_cloud(cloud, P.normalize_by, P.normalized_size)
    c = norm.apply(cloud)
    vs = _interior(c)
    return vs, find_cycle_defects(c, CurveSkeleton.from_raw(norm.apply(verts), edges), voxel_shape=vs)


def _tube_cloud(shape: BenchShape, n: int, *, noise: float = 0.0, sparse_half: bool = False) -> np.ndarray:
    """``n`` surface points; noise in local radii; or the half beyond the median of the longest side
    keeping a tenth of its points."""
    sampler = SurfaceSampler(shape)
    rng = np.random.default_rng(0)
    s = sampler.sample(n, rng)
    pts = s.points + rng.normal(size=s.points.shape) * (noise * s.radius)[:, None]
    if not sparse_half:
        return pts
    from diagnostics_helpers import sparse_half as thin_half

    return thin_half(sampler, n, rng, first=pts)


def _trefoil() -> BenchShape:
    """A trefoil knot whose strands pass about 2.7 tube radii apart, surface to surface."""
    t = np.linspace(0, 2 * np.pi, 48, endpoint=False)
    p = np.column_stack([np.sin(t) + 2 * np.sin(2 * t), np.cos(t) - 2 * np.cos(2 * t), -np.sin(3 * t)]) / 3.0
    return BenchShape("trefoil", "knot", np.empty((0, 3)), (Tube(p, np.full(len(t), 0.086), closed=True),))


def _helix() -> BenchShape:
    """Three turns of radius 1, tube radius 0.15, turns 3 radii apart surface to surface."""
    th = np.linspace(0, 6 * np.pi, 90)
    p = np.column_stack([np.cos(th), np.sin(th), 0.12 * th])
    return BenchShape("helix", "tube", p[[0, -1]], (Tube(p, np.full(len(th), 0.15), start=0, end=1),))


def test_stray_points_around_a_traced_neuron_make_no_tunnel():
    """30k points on the neuron's mesh and 5 % strays in its grown box: the strays' voxels and the rays
    they stop made over a hundred wide tunnels; without the isolated points' voxels there are none, and
    the traced tree gets no ``missing_cycles``."""
    neuron = load_neuron("1734350788")
    tree = neuron.skeleton
    rng = np.random.default_rng(0)
    surface = MeshSampler(neuron.mesh, tree.vertices, np.asarray(tree.radius, float)).sample(30_000, rng).points
    lo, hi = surface.min(axis=0), surface.max(axis=0)
    grow = 0.1 * float(np.linalg.norm(hi - lo))
    cloud = np.vstack([surface, rng.uniform(lo - grow, hi + grow, size=(1500, 3))])
    vs, r = _defects(cloud, tree.vertices, tree.edges)
    assert wide_tunnels(vs.solid()) > 10  # what the count was before
    norm = Normalization.from_cloud(cloud, P.normalize_by, P.normalized_size)
    kept = supported_voxels(norm.apply(cloud), vs)
    assert (vs.occupied & ~kept).sum() > 1000  # most strays dropped, the surface kept
    assert (r.n_cycles, r.shape_tunnels, r.missing) == (0, 0, 0) and r.warnings() == []


def test_noise_bridging_the_strands_of_a_knot_invents_no_tunnel_and_a_cut_is_still_found():
    """Noise of 0.25 local radii: the voxels between strands passed the inside share and the trefoil got
    several tunnels; at the stricter share they are gone, its one tunnel stays."""
    shape = _trefoil()
    cloud = _tube_cloud(shape, 8000, noise=0.25)
    v, e, _ = reference_skeleton(shape)
    vs, r = _defects(cloud, v, e)
    assert wide_tunnels(vs.solid()) > 1
    assert (r.n_cycles, r.shape_tunnels, r.missing) == (1, 1, 0) and r.warnings() == []
    _, cut = _defects(cloud, v, e[3:])
    assert (cut.n_cycles, cut.shape_tunnels, cut.missing) == (0, 1, 1)
    assert [w.code for w in cut.warnings()] == ["missing_cycles"]


def test_a_sparse_half_invents_no_tunnel():
    """A helix whose upper half keeps a tenth of its points: its sparse wall's gaps made tunnels."""
    shape = _helix()
    cloud = _tube_cloud(shape, 8000, sparse_half=True)
    v, e, _ = reference_skeleton(shape)
    vs, r = _defects(cloud, v, e)
    assert wide_tunnels(vs.solid()) > 0
    assert (r.shape_tunnels, r.missing) == (0, 0) and r.warnings() == []


def test_the_thinning_torus_has_one_tunnel_and_its_axis_cut_open_is_below_the_resolution():
    """A ring whose tube thins from 0.25 to 0.02 (noise 0.03): its thin part opens the voxel interior,
    which invents no tunnel there and keeps the ring's one; but the ring is thinner than
    ``open_resolved_diameter`` spacings over its last third, so its axis cut open misses no resolved
    tunnel (the interior's part the sampling resolves has none)."""
    rng = np.random.default_rng(0)
    th, ph = rng.uniform(0, 2 * np.pi, (2, 10_000))
    rad = 0.25 + (0.02 - 0.25) * th / (2 * np.pi)
    ring = 1 + rad * np.cos(ph)
    cloud = np.column_stack([ring * np.cos(th), ring * np.sin(th), rad * np.sin(ph)])
    cloud += rng.normal(size=cloud.shape) * 0.03
    a = np.linspace(0, 2 * np.pi, 64, endpoint=False)
    axis = np.column_stack([np.cos(a), np.sin(a), np.zeros_like(a)])
    edges = np.column_stack([np.arange(64), (np.arange(64) + 1) % 64])
    vs, r = _defects(cloud, axis, edges)
    assert (r.n_cycles, r.shape_tunnels, r.missing) == (1, 1, 0)
    _, cut = _defects(cloud, axis, edges[2:])
    assert (cut.shape_tunnels, cut.missing) == (0, 0)
    norm = Normalization.from_cloud(cloud, P.normalize_by, P.normalized_size)
    shared = dict(inside_share=P.beta_star, strict_share=P.cycles_strict_share)
    assert firm_tunnels(norm.apply(cloud), vs, **shared) == 1
    assert firm_tunnels(norm.apply(cloud), vs, resolved_diameter=P.open_resolved_diameter, **shared) == 0


def test_two_branches_closer_than_the_cloud_resolves_make_no_tunnel():
    """The suite's 4-level tree at 5000 points: two branches 4.4 spacings across pass 2 spacings apart,
    and the voxels join them into a ring thinner than ``open_resolved_diameter`` spacings: the exact
    axis got ``missing_cycles`` (docs/diagnostics.md "Cycles")."""
    from skelcore.benchmark.calibration.skeletons import world

    w = world("synthetic", "tree_4", 5000, "clean", 0)
    v, e, _ = w.ref
    vs, r = _defects(w.cloud, np.asarray(v, float), np.asarray(e, np.int64))
    assert wide_tunnels(vs.solid()) == 1
    assert r.missing == 0 and r.warnings() == []


def _ring(tube: float, gap_voxels: float, n: int = 10_000) -> np.ndarray:
    """``n`` points on a ring of radius 1 and tube radius ``tube``, cut open by a gap of that many
    voxels of the default grid (the box / ``cycles_voxels``) between its two ends."""
    rng = np.random.default_rng(0)
    gap = gap_voxels * 2 * (1 + tube) / P.cycles_voxels
    th, ph = rng.uniform(gap / 2, 2 * np.pi - gap / 2, n), rng.uniform(0, 2 * np.pi, n)
    ring = 1 + tube * np.cos(ph)
    return np.column_stack([ring * np.cos(th), ring * np.sin(th), tube * np.sin(ph)])


def test_two_ends_closer_than_the_grid_resolves_make_no_tunnel():
    """A ring cut open by a gap of 0.8 voxels, its tube 10 spacings across (the sampling resolves it)
    but 2.3 voxels (the box sets the voxel, 4.6 spacings): the voxels close the gap into a ring, as
    they joined two branches of the suite's 4-level tree at 20,000 points. A ring counts only where its
    parts are ``cycles_resolved_voxels`` voxels across; a ring 5.5 voxels across keeps its tunnel."""
    shared = dict(inside_share=P.beta_star, strict_share=P.cycles_strict_share,
                  resolved_diameter=P.open_resolved_diameter)
    cut = Normalization.from_cloud(_ring(0.025, 0.8), P.normalize_by, P.normalized_size).apply(_ring(0.025, 0.8))
    vs = _interior(cut)
    assert wide_tunnels(vs.solid()) == 1
    assert firm_tunnels(cut, vs, **shared) == 1  # the sampling's resolution alone
    assert firm_tunnels(cut, vs, resolved_voxels=P.cycles_resolved_voxels, **shared) == 0
    whole = Normalization.from_cloud(_ring(0.06, 0.0), P.normalize_by, P.normalized_size).apply(_ring(0.06, 0.0))
    assert firm_tunnels(whole, _interior(whole), resolved_voxels=P.cycles_resolved_voxels, **shared) == 1
