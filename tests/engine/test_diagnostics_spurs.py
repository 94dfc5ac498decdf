"""Spurious terminal branches (skelcore/diagnostics/spurs.py)."""

from __future__ import annotations

import numpy as np
import pytest
from diagnostics_helpers import attach_path, normalized

from skelcore import Params, shapes
from skelcore.diagnostics import decompose_branches, find_spurious_branches


@pytest.mark.parametrize("make", [shapes.y_shape, shapes.t_shape, shapes.tree3])
@pytest.mark.parametrize("noise", [0.0, 0.05])
def test_true_skeleton_has_no_spur(make, noise):
    s = make(n=3000, seed=3)
    if noise:
        s = shapes.with_noise(s, noise, seed=3)
    c, curve, samples, _ = normalized(s.cloud, s.curve_vertices, s.curve_edges)
    r = find_spurious_branches(c, curve, samples=samples)
    assert len(r.terminal) == {shapes.y_shape: 3, shapes.t_shape: 3, shapes.tree3: 5}[make]
    assert not r.branch_spurious.any() and r.warnings() == []
    # every true branch reaches far beyond its junction's ball and explains most of its territory
    assert np.all(r.reach[r.terminal] > 5)
    assert np.all(r.unique[r.terminal] > 0.6 * r.territory[r.terminal])


def _bar_vertex(s: shapes.Shape, x: float) -> int:
    on_bar = np.flatnonzero(np.abs(s.curve_vertices[:, 2]) < 1e-12)
    return int(on_bar[np.argmin(np.abs(s.curve_vertices[on_bar, 0] - x))])


@pytest.mark.parametrize("length", [0.5, 0.9, 2.0, 3.0])
def test_spurs_sideways_off_the_bar_are_flagged(length):
    """A spur of 0.5-3 bar radii off the T's bar: inside its junction's ball (short) or poking out
    through the surface, where the bar's own balls explain every point near it."""
    s = shapes.t_shape(n=4000, bar_radius=0.3, seed=4)
    v, e, ids = attach_path(s.curve_vertices, s.curve_edges, _bar_vertex(s, 1.0),
                            s.curve_vertices[_bar_vertex(s, 1.0)] + [0, length * 0.3, 0], 3)
    c, curve, samples, _ = normalized(s.cloud, v, e)
    r = find_spurious_branches(c, curve, samples=samples)
    spur = r.branches.vertex_branch[ids[-1]]
    assert r.spurious.tolist() == [spur]
    assert r.length_radii[spur] == pytest.approx(length, rel=0.1)
    assert r.vertex_flag[ids].all() and r.vertex_flag.sum() == len(ids)
    assert r.sample_flag is not None and r.sample_flag.sum() >= 1
    (w,) = r.warnings()
    assert w.code == "spurious_branches" and "1 of the curve's 4 terminal branches" in w.message
    assert r.length_share == pytest.approx(r.branches.length[spur] / r.branches.length.sum())


def test_ten_spurs_are_all_found_and_nothing_else():
    s = shapes.t_shape(n=4000, seed=5)
    v, e = s.curve_vertices, s.curve_edges
    tips = []
    rng = np.random.default_rng(5)
    for x in np.linspace(-1.4, 1.4, 10):
        a = _bar_vertex(s, x)
        ang = rng.uniform(0, 2 * np.pi)
        v, e, ids = attach_path(v, e, a, v[a] + 0.3 * 1.5 * np.array([0, np.cos(ang), np.sin(ang)]), 2)
        tips.append(ids[-1])
    c, curve, samples, _ = normalized(s.cloud, v, e)
    r = find_spurious_branches(c, curve, samples=samples)
    assert sorted(r.spurious.tolist()) == sorted(r.branches.vertex_branch[tips].tolist())


def test_a_real_side_branch_is_not_a_spur():
    """A branch into a protrusion (the stem of the T, 2 r long here) is justified: it explains the
    stem's points, which the bar's balls do not reach."""
    s = shapes.t_shape(n=4000, stem_length=0.6, seed=6)
    c, curve, samples, _ = normalized(s.cloud, s.curve_vertices, s.curve_edges)
    r = find_spurious_branches(c, curve, samples=samples)
    assert not r.branch_spurious.any()


def test_subsampled_cloud_gives_the_same_verdict():
    s = shapes.t_shape(n=6000, seed=7)
    a = _bar_vertex(s, 0.8)
    v, e, ids = attach_path(s.curve_vertices, s.curve_edges, a, s.curve_vertices[a] + [0, 0, 0.6], 3)
    c, curve, _, _ = normalized(s.cloud, v, e)
    full = find_spurious_branches(c, curve)
    sub = find_spurious_branches(c, curve, params=Params(diag_max_points=1500))
    assert full.subsampled is None and sub.subsampled == 1500
    assert full.spurious.tolist() == sub.spurious.tolist() == [full.branches.vertex_branch[ids[-1]]]


def test_branches_can_be_shared_and_no_terminal_branch_is_fine():
    s = shapes.torus(n=2000)
    c, curve, _, _ = normalized(s.cloud, s.curve_vertices, s.curve_edges)
    b = decompose_branches(curve, cloud=c)
    r = find_spurious_branches(c, curve, branches=b)
    assert r.branches is b and len(r.terminal) == 0 and r.warnings() == []
    assert r.to_dict()["spurious"] == 0


def test_a_stub_under_the_stub_share_is_counted_not_spurious():
    """A spur of 0.5 bar radii stays inside its junction's ball (inside the shape): about 4 % of the
    T's curve, spurious by default, one of the ``stubs`` once that is under ``spur_stub_share``."""
    s = shapes.t_shape(n=4000, bar_radius=0.3, seed=4)
    a = _bar_vertex(s, 1.0)
    v, e, ids = attach_path(s.curve_vertices, s.curve_edges, a, s.curve_vertices[a] + [0, 0.15, 0], 3)
    c, curve, samples, _ = normalized(s.cloud, v, e)
    spur = None
    for share, spurious in ((0.005, True), (0.1, False)):
        r = find_spurious_branches(c, curve, samples=samples, params=Params(spur_stub_share=share))
        spur = r.branches.vertex_branch[ids[-1]]
        assert r.branch_spurious[spur] == spurious and r.stub[spur] == (not spurious)
        assert r.to_dict()["stubs"] == int(not spurious) and r.to_dict()["unresolved"] == 0
    assert r.reach[spur] < 1 and r.warnings() == []


def test_a_part_under_the_resolved_spacings_is_not_judged():
    """A spur of 2 bar radii is spurious; with ``spur_resolved_spacings`` above the bar's radius in
    cloud spacings it is counted unresolved instead, and nothing warns."""
    s = shapes.t_shape(n=4000, bar_radius=0.3, seed=4)
    v, e, ids = attach_path(s.curve_vertices, s.curve_edges, _bar_vertex(s, 1.0),
                            s.curve_vertices[_bar_vertex(s, 1.0)] + [0, 0.6, 0], 3)
    c, curve, samples, _ = normalized(s.cloud, v, e)
    r = find_spurious_branches(c, curve, samples=samples)
    spur = r.branches.vertex_branch[ids[-1]]
    ratio = r.junction_radius[spur] / r.spacing[spur]
    assert ratio > Params().spur_resolved_spacings and r.branch_spurious[spur]
    r = find_spurious_branches(c, curve, samples=samples, params=Params(spur_resolved_spacings=1.01 * ratio))
    assert r.unresolved[spur] and not r.branch_spurious[spur] and r.to_dict()["unresolved"] >= 1
    assert r.warnings() == []
