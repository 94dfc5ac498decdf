"""A broken curve's cut ends are not spurs (skelcore/diagnostics/spur_cuts.py, docs/diagnostics.md
"Spurious branches", rule 6)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.spatial import cKDTree
from diagnostics_helpers import attach_path, normalized

from skelcore import Params, shapes
from skelcore.diagnostics import decompose_branches, find_spurious_branches
from skelcore.diagnostics.spur_cuts import cut_ends

OFF = dataclasses.replace(Params(), spur_cut_gap=0.0)  # the rule off: what the spur test said before


@pytest.fixture(scope="module")
def t_bar():
    s = shapes.t_shape(n=4000, seed=4)
    v, e = s.curve_vertices, s.curve_edges
    bar = np.flatnonzero(np.abs(v[:, 2]) < 1e-12)

    def at(x: float) -> int:
        return int(bar[np.argmin(np.abs(v[bar, 0] - x))])

    a, b = at(0.2), at(0.4)  # the bar cut 0.67-1.33 bar radii from the junction
    cut = ((e[:, 0] == a) & (e[:, 1] == b)) | ((e[:, 0] == b) & (e[:, 1] == a))
    assert cut.sum() == 1
    return s, v, e[~cut], at, (a, b)


def test_a_cut_next_to_the_junction_is_no_spur(t_bar):
    """The stub between the T's junction and the cut stays in the junction's ball: the spur test took
    it for a spur; its tip faces the bar's far piece across a gap the cloud fills."""
    s, v, e, _, (a, _) = t_bar
    c, curve, samples, _ = normalized(s.cloud, v, e)
    before = find_spurious_branches(c, curve, samples=samples, params=OFF)
    stub = int(before.branches.vertex_branch[a])
    assert before.spurious.tolist() == [stub]
    r = find_spurious_branches(c, curve, samples=samples)
    assert r.spurious.tolist() == [] and r.warnings() == []
    assert np.flatnonzero(r.cut_end).tolist() == [stub] and r.to_dict()["cut_ends"] == 1


def test_a_spur_beside_a_cut_is_still_flagged(t_bar):
    """A spur of 2 bar radii off the cut piece, 2 radii from the cut: flagged; both cut ends are not."""
    s, v, e, at, (a, b) = t_bar
    v2, e2, ids = attach_path(v, e, at(1.0), v[at(1.0)] + [0, 0.6, 0], 3)
    c, curve, samples, _ = normalized(s.cloud, v2, e2)
    r = find_spurious_branches(c, curve, samples=samples)
    spur = int(r.branches.vertex_branch[ids[-1]])
    assert r.spurious.tolist() == [spur]
    vb = r.branches.vertex_branch
    assert sorted(np.flatnonzero(r.cut_end).tolist()) == sorted([int(vb[a]), int(vb[b])])
    (w,) = r.warnings()
    assert "1 of the curve's 6 terminal branches" in w.message and "2 more ending where the curve is broken" in w.message
    assert find_spurious_branches(c, curve, samples=samples, params=OFF).spurious.size == 2


def test_a_tip_facing_another_piece_through_the_air_is_no_cut_end():
    """The bar's cloud and curve cut between x = 0.2 and 1.2 / 1.0: the far piece lies ahead within
    spur_cut_gap, but half way the cloud is 1.2 grown balls away (air, not a tube): no cut end."""
    s = shapes.t_shape(n=4000, seed=4)
    x = s.cloud[:, 0]
    cloud = s.cloud[(x < 0.2) | (x > 1.2) | (s.cloud[:, 2] < -0.35)]  # the stem below the bar kept
    v, e = s.curve_vertices, s.curve_edges
    on_bar = (np.abs(v[e, 2]) < 1e-12).all(axis=1)
    ex = v[e, 0]
    e = e[~(on_bar & (ex.min(axis=1) >= 0.2 - 1e-9) & (ex.max(axis=1) <= 1.0 + 1e-9))]
    tip = int(np.flatnonzero((np.abs(v[:, 0] - 0.2) < 1e-9) & (np.abs(v[:, 2]) < 1e-12))[0])
    cn, curve, _, _ = normalized(cloud, v, e)
    br = decompose_branches(curve, cloud=cn)
    term = br.terminal()
    row = list(term).index(int(br.vertex_branch[tip]))
    got = cut_ends(curve, br, term, cKDTree(cn))
    assert got.gap[row] <= Params().spur_cut_gap and got.cos[row] > 0.99
    assert got.fill[row] > 1.1 and not got.cut.any()
