"""Ground-truth metrics (skelcore.metrics.ground_truth; docs/metrics.md 5.3.1): hand-computed answers
(two parallel segments, a Y against a Y with a missing arm, a circle against a cut circle, a shifted
copy) and an independent brute-force implementation on random small graphs."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from skelcore.curve import CurveSkeleton
from skelcore.errors import SkelInputError
from skelcore.metrics.ground_truth import GroundTruthParams as Params
from skelcore.metrics.ground_truth import compare_with_ground_truth, radius_from_cloud

THRESHOLDS = np.arange(1, 21) / 20  # the default: 0.05 .. 1 local radii


def _polyline(points, closed=False) -> CurveSkeleton:
    n = len(points)
    e = [[i, i + 1] for i in range(n - 1)] + ([[n - 1, 0]] if closed else [])
    return CurveSkeleton.from_raw(np.asarray(points, float), np.array(e))


def _segment(a, b, n=10) -> CurveSkeleton:
    t = np.linspace(0, 1, n + 1)[:, None]
    return _polyline((1 - t) * np.asarray(a, float) + t * np.asarray(b, float))


def _star(angles_deg, length=1.0, n=10, z=0.0) -> CurveSkeleton:
    v, e = [np.array([0.0, 0.0, z])], []
    for a in angles_deg:
        d = np.array([math.cos(math.radians(a)), math.sin(math.radians(a)), 0.0])
        prev = 0
        for k in range(1, n + 1):
            v.append(d * length * k / n + [0, 0, z])
            e.append([prev, len(v) - 1])
            prev = len(v) - 1
    return CurveSkeleton.from_raw(np.array(v), np.array(e))


def _ngon(n, radius=1.0):
    a = 2 * np.pi * np.arange(n) / n
    return np.column_stack([radius * np.cos(a), radius * np.sin(a), np.zeros(n)])


def _const(curve, r):
    return np.full(curve.n_vertices, r)


# ---- hand-computed answers ---------------------------------------------------------------------

def test_two_parallel_segments():
    """Reference (0,0,0)-(1,0,0) of radius 0.1; ours the same 0.05 to the side: every distance is 0.05
    = 0.5 radii, within the thresholds 0.5, 0.55, .., 1 (11 of 20)."""
    ref = _segment([0, 0, 0], [1, 0, 0])
    ours = _segment([0, 0.05, 0], [1, 0.05, 0], 7)
    g = compare_with_ground_truth(ours, ref, _const(ref, 0.1))
    assert g.chamfer_to_reference == pytest.approx(0.05) and g.chamfer_from_reference == pytest.approx(0.05)
    assert g.chamfer == pytest.approx(0.05) and g.chamfer_radii == pytest.approx(0.5)
    assert (g.precision, g.recall, g.f1) == pytest.approx((0.55, 0.55, 0.55))
    assert g.endpoints == (2, 2, 2) and (g.endpoint_precision, g.endpoint_recall) == (1.0, 1.0)
    assert g.junctions == (0, 0, 0) and math.isnan(g.junction_precision) and math.isnan(g.junction_recall)
    assert g.length_ratio == pytest.approx(1.0) and g.cycle_error == 0
    assert (g.branches, g.splits, g.merges) == ((1, 1), 0, 0)
    far = compare_with_ground_truth(_segment([0, 0.15, 0], [1, 0.15, 0]), ref, _const(ref, 0.1))
    assert (far.precision, far.recall, far.f1) == (0.0, 0.0, 0.0)
    assert far.chamfer_radii == pytest.approx(1.5)
    assert far.endpoints == (2, 2, 2)  # 1.5 radii: within the 2 radii of a node
    assert (far.splits, far.merges) == (0, 0)  # nothing associated: no branch is within 1 radius


def test_a_y_against_a_y_with_a_missing_arm():
    """Arms of length 1 at 90, 210, 330 degrees, radius 0.1; ours lacks the 330 arm. A point at s
    along the missing arm is s from ours (its nearest point is the centre), so the reference's mean
    distance is (1/3)(1/2), recall at t radii is (2 + 0.1 t) / 3; our two arms form one branch through
    the centre covering two reference branches: one merge."""
    ref = _star([90, 210, 330])
    ours = _star([90, 210])
    fine = Params(sample_step=0.01)
    g = compare_with_ground_truth(ours, ref, _const(ref, 0.1), params=fine)
    assert g.chamfer_to_reference == pytest.approx(0.0, abs=1e-12)
    assert g.chamfer_from_reference == pytest.approx(1 / 6)
    assert g.precision == 1.0
    rec = (2 + 0.1 * THRESHOLDS) / 3
    assert g.recall == pytest.approx(rec.mean(), abs=2e-4)  # the samples are 0.001 apart
    assert g.f1 == pytest.approx(np.mean(2 * rec / (1 + rec)), abs=2e-4)
    assert g.junctions == (0, 1, 0) and g.junction_recall == 0.0 and math.isnan(g.junction_precision)
    assert g.endpoints == (2, 3, 2) and g.endpoint_precision == 1.0 and g.endpoint_recall == pytest.approx(2 / 3)
    assert g.length_ratio == pytest.approx(2 / 3) and g.length == pytest.approx((2.0, 3.0))
    assert (g.branches, g.splits, g.merges) == ((1, 3), 0, 1)
    same = compare_with_ground_truth(ref, ref, _const(ref, 0.1))
    assert (same.f1, same.junction_recall, same.splits, same.merges) == (1.0, 1.0, 0, 0)
    assert same.chamfer == pytest.approx(0.0, abs=1e-12)


def test_a_circle_against_a_cut_circle():
    """A 24-gon of radius 1 (tube radius 0.1) and the same with one edge removed: one cycle less, two
    endpoints that the reference does not have, the missing chord of length L at mean distance L / 4
    from the cut ends (1/24 of the reference's length)."""
    n = 24
    ref = _polyline(_ngon(n), closed=True)
    ours = _polyline(_ngon(n))
    g = compare_with_ground_truth(ours, ref, _const(ref, 0.1), params=Params(sample_step=0.01))
    chord = 2 * math.sin(math.pi / n)
    assert (g.cycles, g.cycle_error) == ((0, 1), -1)
    assert g.endpoints == (2, 0, 0) and g.endpoint_precision == 0.0 and math.isnan(g.endpoint_recall)
    assert g.length_ratio == pytest.approx((n - 1) / n)
    assert g.chamfer_to_reference == pytest.approx(0.0, abs=1e-12)
    assert g.chamfer_from_reference == pytest.approx(chord / 4 / n, rel=1e-3)
    covered = np.minimum(1.0, 2 * THRESHOLDS * 0.1 / chord)  # of the missing chord, within t radii
    assert g.recall == pytest.approx(np.mean((n - 1) / n + covered / n), abs=1e-4)
    assert g.precision == 1.0
    assert (g.branches, g.splits, g.merges) == ((1, 1), 0, 0)


@pytest.mark.parametrize("shift, within", [(0.03, 15), (0.12, 0)])
def test_a_shifted_copy(shift, within):
    """The Y moved by ``shift`` across its plane: every distance is the shift (0.3 or 1.2 radii);
    nodes stay within 2 radii, branches are associated only within 1 radius."""
    ref = _star([90, 210, 330])
    ours = _star([90, 210, 330], z=shift)
    g = compare_with_ground_truth(ours, ref, _const(ref, 0.1))
    assert g.chamfer_to_reference == pytest.approx(shift) and g.chamfer_from_reference == pytest.approx(shift)
    assert g.chamfer_radii == pytest.approx(shift / 0.1)
    assert (g.precision, g.recall) == pytest.approx((within / 20, within / 20))
    assert g.junctions == (1, 1, 1) and g.endpoints == (3, 3, 3)
    assert (g.splits, g.merges) == (0, 0)
    assert g.length_ratio == pytest.approx(1.0)


def test_thresholds_follow_the_local_radius():
    """The same 0.05 offset is 0.25 radii of a thick reference and 1 radius of a thin one."""
    ref = _segment([0, 0, 0], [1, 0, 0])
    ours = _segment([0, 0.05, 0], [1, 0.05, 0])
    thick = compare_with_ground_truth(ours, ref, _const(ref, 0.2))
    thin = compare_with_ground_truth(ours, ref, _const(ref, 0.05))
    assert thick.precision == pytest.approx(16 / 20) and thin.precision == pytest.approx(1 / 20)


def test_radius_from_the_cloud_when_the_reference_has_none():
    rng = np.random.default_rng(0)
    n = 20000
    a, x = rng.uniform(0, 2 * np.pi, n), rng.uniform(-0.2, 1.2, n)
    cloud = np.column_stack([x, 0.1 * np.cos(a), 0.1 * np.sin(a)])
    ref = _segment([0, 0, 0], [1, 0, 0])
    assert np.allclose(radius_from_cloud(ref.vertices, cloud, 8), 0.1, rtol=0.02)
    ours = _segment([0, 0.05, 0], [1, 0.05, 0])
    est = compare_with_ground_truth(ours, ref, None, cloud)
    exact = compare_with_ground_truth(ours, ref, _const(ref, 0.1))
    assert est.radius_source == "cloud" and exact.radius_source == "reference"
    assert est.chamfer_radii == pytest.approx(exact.chamfer_radii, rel=0.03)


def test_bad_inputs_are_one_line_errors():
    ref = _segment([0, 0, 0], [1, 0, 0])
    with pytest.raises(SkelInputError, match="need the reference's radius or the cloud"):
        compare_with_ground_truth(ref, ref)
    with pytest.raises(SkelInputError, match="radius has 3 values for 11 vertices"):
        compare_with_ground_truth(ref, ref, np.ones(3))
    with pytest.raises(SkelInputError, match="finite and > 0"):
        compare_with_ground_truth(ref, ref, np.zeros(11))
    lone = CurveSkeleton.from_raw(np.zeros((1, 3)), None)
    with pytest.raises(SkelInputError, match="no edges"):
        compare_with_ground_truth(ref, lone, np.ones(1))
    with pytest.raises(ValueError):
        Params(thresholds=0)


def test_a_curve_without_edges_is_scored_by_its_vertices():
    ref = _segment([0, 0, 0], [1, 0, 0])
    dots = CurveSkeleton.from_raw(np.array([[0.5, 0.02, 0.0], [0.2, 0.5, 0.0]]), None)
    g = compare_with_ground_truth(dots, ref, _const(ref, 0.1))
    assert g.chamfer_to_reference == pytest.approx((0.02 + 0.5) / 2)
    assert g.precision == pytest.approx(np.mean([(0.02 <= t * 0.1 + 1e-12) * 0.5 for t in THRESHOLDS]))
    assert g.branches == (0, 1) and g.length == (0.0, 1.0)


# ---- an independent brute-force implementation -------------------------------------------------

def _bf_samples(v, e, step, radius=None):
    out = []
    for k, (i, j) in enumerate(e):
        a, b = v[i], v[j]
        length = float(np.linalg.norm(b - a))
        n = max(1, math.ceil(length / step))
        for m in range(n):
            t = (m + 0.5) / n
            r = None if radius is None else radius[i] + t * (radius[j] - radius[i])
            out.append((a + t * (b - a), length / n, k, r))
    return out


def _bf_nearest(v, e, p, radius=None):
    best = (math.inf, None)
    for i, j in e:
        a, b = v[i], v[j]
        ab = b - a
        t = 0.0 if ab @ ab == 0 else min(1.0, max(0.0, float((p - a) @ ab / (ab @ ab))))
        d = float(np.linalg.norm(a + t * ab - p))
        if d < best[0]:
            best = (d, None if radius is None else radius[i] + t * (radius[j] - radius[i]))
    return best


def _bf_branches(n_vertices, e):
    deg = [0] * n_vertices
    inc = [[] for _ in range(n_vertices)]
    for k, (i, j) in enumerate(e):
        deg[i] += 1
        deg[j] += 1
        inc[i].append(k)
        inc[j].append(k)
    label = [-1] * len(e)
    count = 0

    def walk(start_vertex, edge):
        nonlocal count
        cur_v, cur_e = start_vertex, edge
        while label[cur_e] == -1:
            label[cur_e] = count
            i, j = e[cur_e]
            nxt = j if i == cur_v else i
            if deg[nxt] != 2:
                break
            cur_e = inc[nxt][0] if inc[nxt][1] == cur_e else inc[nxt][1]
            cur_v = nxt
        count += 1

    for vtx in range(n_vertices):
        if deg[vtx] != 2:
            for k in inc[vtx]:
                if label[k] == -1:
                    walk(vtx, k)
    for k in range(len(e)):
        if label[k] == -1:
            walk(e[k][0], k)
    return label, count


def _bf_cycles(n_vertices, e):
    parent = list(range(n_vertices))

    def find(x):
        while parent[x] != x:
            x = parent[x]
        return x

    for i, j in e:
        parent[find(i)] = find(j)
    comps = len({find(x) for x in range(n_vertices)})
    return len(e) - n_vertices + comps


def _bf_match(ours, ref, reach):
    small, big, swap = (ours, ref, False) if len(ours) <= len(ref) else (ref, ours, True)
    best = 0
    for perm in itertools.permutations(range(len(big)), len(small)):
        count = 0
        for a, b in enumerate(perm):
            o, r = (big[b], small[a]) if swap else (small[a], big[b])
            j = a if swap else b
            count += np.linalg.norm(o - r) <= reach[j] * (1 + 1e-9)
        best = max(best, count)
    return best


def _brute_force(ours: CurveSkeleton, ref: CurveSkeleton, radius: np.ndarray, p: Params) -> dict:
    v_o, e_o, v_r, e_r = ours.vertices, ours.edges.tolist(), ref.vertices, ref.edges.tolist()
    len_o = sum(float(np.linalg.norm(v_o[j] - v_o[i])) for i, j in e_o)
    len_r = sum(float(np.linalg.norm(v_r[j] - v_r[i])) for i, j in e_r)
    step = max(p.sample_step * float(min(radius)), (len_o + len_r) / 200_000)
    s_r = _bf_samples(v_r, e_r, step, radius)
    s_o = _bf_samples(v_o, e_o, step)
    ours_d = [(_bf_nearest(v_r, e_r, x, radius), w) for x, w, _, _ in s_o]
    ref_d = [(_bf_nearest(v_o, e_o, x)[0], w, r) for x, w, _, r in s_r]
    w_o, w_r = sum(w for _, w in ours_d), sum(w for _, w, _ in ref_d)
    slack = 1 + 1e-9
    ts = p.threshold_max * np.arange(1, p.thresholds + 1) / p.thresholds
    prec = [sum(w for (d, r), w in ours_d if d <= t * slack * r) / w_o for t in ts]
    rec = [sum(w for d, w, r in ref_d if d <= t * slack * r) / w_r for t in ts]
    f1 = [2 * a * b / (a + b) if a + b > 0 else 0.0 for a, b in zip(prec, rec)]
    deg_o, deg_r = np.bincount(ours.edges.ravel(), minlength=len(v_o)), np.bincount(ref.edges.ravel(), minlength=len(v_r))
    nodes = {}
    for kind, so, sr in (("junctions", deg_o >= 3, deg_r >= 3), ("endpoints", deg_o == 1, deg_r == 1)):
        nodes[kind] = (int(so.sum()), int(sr.sum()), _bf_match(v_o[so], v_r[sr], p.match_radii * radius[sr]))
    lab_r, n_r = _bf_branches(len(v_r), e_r)
    lab_o, n_o = _bf_branches(len(v_o), e_o)
    junction = [j for j in range(len(v_r)) if deg_r[j] >= 3]
    overlap: dict = {}
    reach = p.branch_radii
    for (x, w, k, r), (d, _, _) in zip(s_r, ref_d):
        if d > reach * r * slack:
            continue
        if junction:
            dj = [(float(np.linalg.norm(x - v_r[j])), j) for j in junction]
            dist, j = min(dj)
            if dist <= reach * radius[j]:
                continue
        nearest = min(range(len(s_o)), key=lambda m: float(np.linalg.norm(s_o[m][0] - x)))
        key = (lab_r[k], lab_o[s_o[nearest][2]])
        overlap[key] = overlap.get(key, 0.0) + w
    mean_r = {}
    for x, w, k, r in s_r:
        a, b = mean_r.get(lab_r[k], (0.0, 0.0))
        mean_r[lab_r[k]] = (a + w * r, b + w)
    assoc = {key for key, length in overlap.items() if length >= reach * mean_r[key[0]][0] / mean_r[key[0]][1]}
    splits = sum(max(0, len({c for b, c in assoc if b == bb}) - 1) for bb in range(n_r))
    merges = sum(max(0, len({b for b, c in assoc if c == cc}) - 1) for cc in range(n_o))
    c_to = sum(d * w for (d, _), w in ours_d) / w_o
    c_from = sum(d * w for d, w, _ in ref_d) / w_r
    return {
        "chamfer_to_reference": c_to, "chamfer_from_reference": c_from, "chamfer": (c_to + c_from) / 2,
        "chamfer_radii": (sum(d / r * w for (d, r), w in ours_d) / w_o + sum(d / r * w for d, w, r in ref_d) / w_r) / 2,
        "precision": float(np.mean(prec)), "recall": float(np.mean(rec)), "f1": float(np.mean(f1)),
        "junctions": nodes["junctions"], "endpoints": nodes["endpoints"],
        "cycles": (_bf_cycles(len(v_o), e_o), _bf_cycles(len(v_r), e_r)),
        "length": (len_o, len_r), "branches": (n_o, n_r), "splits": splits, "merges": merges,
    }


def _random_pair(rng):
    n = int(rng.integers(5, 9))
    v = rng.uniform(0, 1, (n, 3))
    e = [[int(rng.integers(0, k)), k] for k in range(1, n)]  # a random tree
    if rng.uniform() < 0.6:
        e.append([0, n - 1])  # a cycle
    ref = CurveSkeleton.from_raw(v, np.array(e))
    keep = [x for x in e if rng.uniform() > 0.25]
    extra = rng.uniform(0, 1, (2, 3))
    v2 = np.vstack([v + rng.normal(0, 0.04, v.shape), extra])
    keep += [[n, int(rng.integers(0, n))], [n + 1, n]]
    ours = CurveSkeleton.from_raw(v2, np.array(keep))
    return ours, ref, rng.uniform(0.05, 0.25, ref.n_vertices)


@pytest.mark.parametrize("seed", range(6))
def test_agrees_with_a_brute_force_implementation(seed):
    rng = np.random.default_rng(seed)
    ours, ref, radius = _random_pair(rng)
    p = Params(sample_step=0.5, thresholds=10, threshold_max=1.5)
    got = compare_with_ground_truth(ours, ref, radius, params=p).to_dict()
    want = _brute_force(ours, ref, radius, p)
    for key, value in want.items():
        if isinstance(value, tuple):
            assert tuple(got[key]) == pytest.approx(value, rel=1e-9, abs=1e-12), key
        else:
            assert got[key] == pytest.approx(value, rel=1e-9, abs=1e-12), key
    assert got["cycle_error"] == want["cycles"][0] - want["cycles"][1]


def test_isolated_vertices_are_not_part_of_a_curve_with_edges():
    ref = _segment([0, 0, 0], [1, 0, 0])
    ours = _segment([0, 0.05, 0], [1, 0.05, 0])
    stray = CurveSkeleton.from_raw(np.vstack([ours.vertices, [[3.0, 3.0, 3.0]]]), ours.edges)
    ref_stray = CurveSkeleton.from_raw(np.vstack([ref.vertices, [[0.5, 0.05, 0.0]]]), ref.edges)
    a = compare_with_ground_truth(ours, ref, _const(ref, 0.1)).to_dict()
    b = compare_with_ground_truth(stray, ref_stray, np.append(_const(ref, 0.1), 0.3)).to_dict()
    assert str(a) == str(b)  # NaN == NaN as text
