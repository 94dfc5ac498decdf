"""Branches along the surface (skelcore/diagnostics/surface.py, docs/diagnostics.md "Along the
surface"): a tube's axis moved towards its wall is flagged, the exact axis and a small offset are not,
a traced neuron is not judged, and the message names the branch with finite numbers."""

from __future__ import annotations

import numpy as np
import pytest

import skelcore
from skelcore import Params, shapes
from skelcore.curve import CurveSkeleton
from skelcore.diagnostics.surface import SurfaceRuns
from skelcore.diagnostics.trust import DEFECT_CODES
from skelcore.diagnostics.record import DEFECT_BITS


@pytest.fixture(scope="module")
def tube():
    return shapes.cylinder(3000, radius=0.5, length=4.0, seed=1)


def _moved(sh, share: float) -> CurveSkeleton:
    """The exact axis, every vertex moved ``share`` of the radius (0.5) towards the wall along +x."""
    return CurveSkeleton.from_raw(sh.curve_vertices + [0.5 * share, 0.0, 0.0], sh.curve_edges)


def _surface(ev):
    return [w for w in ev.warnings if w.code == "along_surface"]


@pytest.mark.parametrize("share", [0.6, 0.8])
def test_an_axis_moved_towards_the_wall_is_flagged(tube, share):
    ev = skelcore.evaluate(tube.cloud, None, _moved(tube, share))
    got = _surface(ev)
    assert len(got) == 1 and got[0].message.startswith("branch 0 runs along the surface for ")
    part = ev.diagnostics.part("along_surface")
    assert [b["id"] for b in part["branches"]] == [0]
    # Eq. 11 on a round section: the sample lies c x r from the wall, c = 1 - the offset's share
    assert part["branches"][0]["centeredness"] == pytest.approx(1 - share, abs=0.05)
    assert (ev.diagnostics.arrays["curve_edge_defects"] & DEFECT_BITS["along_surface"]).all()
    assert "along_surface" in DEFECT_CODES


@pytest.mark.parametrize("share", [0.0, 0.2])
def test_the_axis_and_a_small_offset_are_quiet(tube, share):
    ev = skelcore.evaluate(tube.cloud, None, _moved(tube, share))
    assert not _surface(ev) and "along_surface" not in ev.not_computed
    assert ev.diagnostics.part("along_surface")["branches"] == []


def _traced_tubes(points: int, seed: int = 0):
    """The tuning neuron 1734350788's traced SWC and ``points`` samples of the tubes of its traced radii
    around its edges (by area; its mesh takes seconds to read)."""
    from skelcore.io.loaders import load_curve

    sk = load_curve("resources/neurons/1734350788.swc")
    v, e, r = np.asarray(sk.vertices), np.asarray(sk.edges), np.asarray(sk.radius)
    rng = np.random.default_rng(seed)
    a, b = v[e[:, 0]], v[e[:, 1]]
    re = 0.5 * (r[e[:, 0]] + r[e[:, 1]])
    area = re * np.linalg.norm(b - a, axis=1)
    k = rng.choice(len(e), points, p=area / area.sum())
    d = (b - a)[k] / np.maximum(np.linalg.norm((b - a)[k], axis=1, keepdims=True), 1e-12)
    g = np.cross(d, [0.0, 0.0, 1.0])
    flat = np.linalg.norm(g, axis=1) < 1e-6
    g[flat] = np.cross(d[flat], [1.0, 0.0, 0.0])
    g /= np.linalg.norm(g, axis=1, keepdims=True)
    ang = rng.uniform(0, 2 * np.pi, points)[:, None]
    around = np.cos(ang) * g + np.sin(ang) * np.cross(d, g)
    return v, e, a[k] + rng.uniform(size=(points, 1)) * (b - a)[k] + re[k, None] * around


def test_a_traced_neuron_is_not_judged():
    """A tuning neuron's arbor (12,000 points): the centeredness slab is about 11 of the curve's median
    local radii thick, its "sections" are stretches of neurite and half its samples fall under the
    threshold; not judged, it is quiet, and says why. Judged all the same, it would flag branches."""
    from skelcore.diagnostics.branches import decompose_branches
    from skelcore.diagnostics.surface import find_along_surface
    from skelcore.geometry import Normalization, kd_tree
    from skelcore.metrics.centeredness import curve_centeredness
    from skelcore.metrics.curve_sampling import sample_curve

    p = Params()
    v, e, cloud = _traced_tubes(12_000)
    norm = Normalization.from_cloud(cloud, p.normalize_by, p.normalized_size)
    cn = norm.apply(cloud)
    curve = CurveSkeleton.from_raw(norm.apply(v), e[:800])  # a subtree: its samples score in a second
    s = sample_curve(curve, p.curve_samples, collinear_cos=p.collinear_cos)
    c = curve_centeredness(cn, s.points, s.directions, params=p)
    tree = kd_tree(cn)
    br = decompose_branches(curve, cloud=cn, sample_edge=s.edge, cloud_tree=tree)
    radius = float(np.median(br.radius_median))
    bounded = np.ones(len(s))  # every sample judged: the strictest case
    got = find_along_surface(curve, br, s, c, bounded, tree, radius, p)
    assert 8 < got.slab_radii < 16 and not len(got.flagged) and not got.warnings()
    assert "surface_slab_radii = 4" in got.unchecked
    judged = find_along_surface(curve, br, s, c, bounded, tree, radius, Params(surface_slab_radii=100.0))
    assert len(judged.flagged) and judged.unchecked is None


def test_the_evaluation_names_an_unjudged_curve(tube):
    ev = skelcore.evaluate(tube.cloud, None, _moved(tube, 0.7), params=Params(surface_slab_radii=0.1))
    assert not _surface(ev) and "surface_slab_radii = 0.1" in ev.not_computed["along_surface"]


def test_the_message_names_the_longest_branch_and_never_nan():
    runs = SurfaceRuns(sample_off=np.zeros(4, bool), branch_samples=np.array([5, 3, 4]),
                       branch_off=np.array([4, 0, 3]), branch_length=np.array([0.12, 0.0, 0.3]),
                       branch_centeredness=np.array([0.1, np.nan, 0.25]), radius=0.025,
                       flagged=np.array([0, 2]), params=Params())
    [w] = runs.warnings()
    assert w.message == ("2 branches run along the surface, the longest branch 2 for 12 local radii "
                         "(0.25 cross-section radii from the wall, median)")
    runs.radius = 0.0  # no radius known: the length clause goes
    assert runs.warnings()[0].message == ("2 branches run along the surface, the longest branch 2 "
                                          "(0.25 cross-section radii from the wall, median)")
    assert "nan" not in str(runs.to_dict()).lower()


def test_the_calibrations_truth_reads_the_move_across_the_axis():
    """``offset`` moves every vertex 0.8 radii one way: true when most of it is across the tube's axis;
    the intact skeleton and one moved 0.2 radii are false."""
    from dataclasses import replace

    from skelcore.benchmark.calibration.skeletons import make_kind, world
    from skelcore.benchmark.calibration.truth import along_surface_truth
    from skelcore.benchmark.skeleton_defects import offset

    w = world("synthetic", "tube_a", 1200, "clean", 0)
    moved = make_kind("offset", w, "tube_a", 0)
    intact = make_kind("intact", w, "tube_a", 0)
    assert along_surface_truth(moved, w) == 1 and along_surface_truth(intact, w) == 0
    v, e, r = (np.asarray(x) for x in w.ref)
    little = offset(v.astype(float), e, r.astype(float), 0.2, np.random.default_rng(0))[0]
    assert along_surface_truth(replace(moved, vertices=little), w) == 0


def test_the_kimimaro_hammer_knob_is_flagged_and_its_head_is_centred():
    """kimimaro's hammer (docs/diagnostics.md "Along the surface", "The hammer's head"): the knob's two
    branches along opposite walls are flagged; the head's branches run within a fifth of the head's
    half-width of its section's centre (by the cloud alone) and their judged samples have c above 0.8,
    so the head is quiet because its branches are centred, not because no sample of it is judged; moved
    towards a face, a head branch is flagged."""
    pytest.importorskip("kimimaro")
    from skelcore import adapters
    from skelcore.io.loaders import load_cloud

    cloud = np.asarray(load_cloud("resources/scans/hammer_4096.ply"), float)
    curve = adapters.run("kimimaro", cloud).curve
    ev = skelcore.evaluate(cloud, None, curve, workers=1)
    ctx = ev.source.ctx
    cd = ctx.results["curve defects"]
    sb, runs = cd.branches.sample_branch, cd.surface
    pts = ctx.norm.invert(ctx.samples.points)  # the scan's units: the head is y > 86
    top = np.array([pts[sb == b, 1].min() if (sb == b).any() else -np.inf for b in range(len(cd.branches))])
    knob = np.flatnonzero(np.array([pts[sb == b, 1].max() if (sb == b).any() else np.inf
                                    for b in range(len(cd.branches))]) < -160)
    head = np.flatnonzero(top > 86)
    assert len(head) >= 3 and set(runs.flagged) & set(knob) and not set(runs.flagged) & set(head)
    on_head = np.isin(sb, head)
    c = np.asarray(ctx.results["curve centeredness"], float)[on_head]
    judged = c[c > 0]
    assert len(judged) >= 10 and np.median(judged) > 0.8
    # each head sample's offset from its section's centre (the head's points within 2 units of its z)
    cloud_head = cloud[cloud[:, 1] > 86]
    share = []
    for p in pts[on_head]:
        sec = cloud_head[np.abs(cloud_head[:, 2] - p[2]) < 2.0][:, :2]
        lo, hi = sec.min(axis=0), sec.max(axis=0)
        share.append(np.max(np.abs(p[:2] - (lo + hi) / 2) / ((hi - lo) / 2)))
    assert np.median(share) < 0.2
    # the head's vertices moved 12 units towards its +x face (0.65 of the middle's half-width): seen
    v = np.asarray(curve.vertices, float).copy()
    v[v[:, 1] > 88, 0] += 12.0
    moved = skelcore.evaluate(cloud, None, CurveSkeleton.from_raw(v, curve.edges), workers=1)
    mcd = moved.source.ctx.results["curve defects"]
    mpts, msb = moved.source.ctx.norm.invert(moved.source.ctx.samples.points), mcd.branches.sample_branch
    assert any((msb == b).any() and mpts[msb == b, 1].min() > 86 for b in mcd.surface.flagged)
