"""The other communities' ground-truth metrics (docs/metrics.md 5.3.2) against answers worked out by
hand, and ESA / DSA / PDS against swclib's SSD metric on a shipped neuron and perturbed copies."""

from __future__ import annotations

import math

import numpy as np
import pytest

from skelcore.curve import CurveSkeleton
from skelcore.metrics.gt_community import community_metrics, root_to_leaf_paths


def _polyline(points, n: int = 31):
    """A polyline through ``points`` with n vertices per leg: (vertices, edges)."""
    pts = np.asarray(points, float)
    v = [pts[0]]
    for a, b in zip(pts[:-1], pts[1:]):
        v += list(np.linspace(a, b, n)[1:])
    v = np.array(v)
    return v, np.column_stack([np.arange(len(v) - 1), np.arange(1, len(v))])


def _curve(parts):
    vs, es, off = [], [], 0
    for v, e in parts:
        vs.append(v)
        es.append(e + off)
        off += len(v)
    return CurveSkeleton.from_raw(np.vstack(vs), np.vstack(es))


SEG = _curve([_polyline([[0, 0, 0], [10, 0, 0]])])
R_SEG = np.full(SEG.n_vertices, 1.0)


def test_identity_is_perfect():
    m = community_metrics(SEG, SEG, R_SEG)
    for k in ("diag_f1_1", "diag_f1_5", "branch_f1", "path_f1"):
        assert m[k] == 1.0
    assert m["esa"] == m["dsa"] == m["pds"] == 0.0
    assert m["betti0_error"] == m["betti1_error"] == 0.0
    assert math.isclose(m["dup_precision"], 1.0) and math.isnan(m["radius_error"])


@pytest.mark.parametrize("shift, f1_1, f1_2, dsa, pds", [(0.15, 0.0, 1.0, 0.0, 0.0), (0.3, 0.0, 0.0, 0.03, 1.0)])
def test_shifted_copy_in_diagonal_units(shift, f1_1, f1_2, dsa, pds):
    # diagonal 10: a shift of 0.15 is 1.5 % (outside 1 %, within 2 %); 0.3 is substantial (> 2 %)
    m = community_metrics(CurveSkeleton.from_raw(SEG.vertices + [0, shift, 0], SEG.edges), SEG, R_SEG)
    assert m["diag_f1_1"] == f1_1 and m["diag_f1_2"] == f1_2 and m["diag_f1_5"] == 1.0
    assert math.isclose(m["esa"], shift / 10) and math.isclose(m["chamfer_diag"], shift / 10)
    assert math.isclose(m["dsa"], dsa) and math.isclose(m["pds"], pds)


def test_duplicate_aware_precision_and_betti0():
    # two copies 0.2 r either side: plain precision 1, but the reference vouches for 10 + 2 r of 20
    two = _curve([(SEG.vertices + [0, 0.2, 0], SEG.edges), (SEG.vertices - [0, 0.2, 0], SEG.edges)])
    m = community_metrics(two, SEG, R_SEG)
    assert m["diag_precision_2"] == 1.0 and m["branch_precision"] == 1.0
    assert math.isclose(m["dup_precision"], 12 / 20)
    assert m["betti0_error"] == 1.0


def test_missing_arm_branch_and_path_scores():
    # a Y with arms of 3 (r = 0.5), vertex 0 the tip of arm 1 (the root); ours lacks arm 3
    arm1, arm2, arm3 = [[-3, 0, 0], [0, 0, 0]], [[0, 0, 0], [0, 3, 0]], [[0, 0, 0], [0, 0, 3]]
    v1, e1 = _polyline(arm1)
    v2, _ = _polyline(arm2)
    v3, _ = _polyline(arm3)
    junction = len(v1) - 1
    v = np.vstack([v1, v2[1:], v3[1:]])
    # arm 2 and arm 3 start at the junction (the last vertex of arm 1)
    n1, n2 = len(v1), len(v2) - 1
    e_arm2 = np.column_stack([np.r_[junction, np.arange(n1, n1 + n2 - 1)], np.arange(n1, n1 + n2)])
    e_arm3 = np.column_stack([np.r_[junction, np.arange(n1 + n2, n1 + 2 * n2 - 1)], np.arange(n1 + n2, n1 + 2 * n2)])
    ref = CurveSkeleton.from_raw(v, np.vstack([e1, e_arm2, e_arm3]))
    ours = CurveSkeleton.from_raw(v[: n1 + n2], np.vstack([e1, e_arm2]))
    assert len(root_to_leaf_paths(ref, 0)) == 2 and len(root_to_leaf_paths(ours, 0)) == 1
    m = community_metrics(ours, ref, np.full(ref.n_vertices, 0.5))
    # arm 3 is covered only within 0.5 of the junction (1/6 < 0.8): 2 of 3 branches found; ours is one branch
    assert math.isclose(m["branch_recall"], 2 / 3) and m["branch_precision"] == 1.0
    # paths: root -> tip 2 matched; root -> tip 3 covered (3 + 0.5) / 6 < 0.8
    assert m["path_precision"] == 1.0 and m["path_recall"] == 0.5 and math.isclose(m["path_f1"], 2 / 3)
    assert m["paths"] == 1 and m["paths_reference"] == 2


def test_spur_and_radius_error():
    spur = _curve([_polyline([[0, 0, 0], [10, 0, 0]]), _polyline([[5, 0, 0], [5, 3, 0]])])
    # the spur's first vertex duplicates the middle vertex: join them through from_raw's edges
    v, e = spur.vertices, spur.edges.copy()
    mid = int(np.argmin(np.linalg.norm(v[:31] - [5, 0, 0], axis=1)))
    e[e == 31] = mid
    joined = CurveSkeleton.from_raw(v, e)
    m = community_metrics(joined, SEG, np.full(SEG.n_vertices, 0.5))
    # three branches of ours (two halves, the spur covered only 0.5 of 3): 2 / 3; paths: 1 of 2 ours
    assert math.isclose(m["branch_precision"], 2 / 3) and m["branch_recall"] == 1.0
    assert m["path_precision"] == 0.5 and m["path_recall"] == 1.0
    wide = community_metrics(SEG, SEG, R_SEG, curve_radius=np.full(SEG.n_vertices, 1.2))
    assert math.isclose(wide["radius_error"], 0.2)


def test_ring_cycles_and_no_paths():
    t = np.linspace(0, 2 * np.pi, 60, endpoint=False)
    v = np.column_stack([np.cos(t) * 5, np.sin(t) * 5, np.zeros(60)])
    ring = CurveSkeleton.from_raw(v, np.column_stack([np.arange(60), (np.arange(60) + 1) % 60]))
    cut = CurveSkeleton.from_raw(v, np.column_stack([np.arange(59), np.arange(1, 60)]))
    m = community_metrics(cut, ring, np.full(60, 0.5))
    assert m["betti1_error"] == -1.0 and m["betti0_error"] == 0.0
    assert math.isnan(m["path_f1"])  # a ring has no leaf: no root-to-leaf path to find


# ---- swclib (MIT): its SSD metric is Vaa3D's ESA / DSA / PDS on nodes resampled every S ------

def _swc_rows(path, n: int = 400):
    """The first ``n`` nodes of an SWC whose parents are among them (a sub-arbor: parents come first)."""
    rows = np.loadtxt(path, comments="#", ndmin=2)[:n]
    keep = np.isin(rows[:, 6], np.r_[-1, rows[:, 0]])
    return rows[keep]


def _write_swc(path, rows):
    np.savetxt(path, rows, fmt=["%d", "%d", "%.6f", "%.6f", "%.6f", "%.6f", "%d"])


@pytest.mark.parametrize("kind", ["same", "shift", "noise"])
def test_esa_dsa_pds_agree_with_swclib(tmp_path, kind):
    ssd = pytest.importorskip("swclib.metrics.ssd_metric")
    from skelcore.benchmark.neurons import NEURON_DIR
    from skelcore.io import load_curve

    rows = _swc_rows(NEURON_DIR / "722817260.swc")
    gold = tmp_path / "gold.swc"
    _write_swc(gold, rows)
    ref = load_curve(gold)
    diag = float(np.linalg.norm(np.ptp(ref.vertices, axis=0)))
    s = 0.02 * diag  # swclib's min_distance = our substantial distance (2 % of the diagonal)
    pert = rows.copy()
    rng = np.random.default_rng(5)
    if kind == "shift":
        pert[:, 2:5] += np.array([3.0, 0.0, 0.0]) * s
    elif kind == "noise":
        pert[:, 2:5] += rng.normal(scale=1.5 * s, size=(len(rows), 3))
    pred = tmp_path / "pred.swc"
    _write_swc(pred, pert)
    theirs = ssd.SSDMetric(min_distance=s).run(str(gold), str(pred))
    ours = community_metrics(load_curve(pred), ref, ref.radius)
    if kind == "same":
        assert theirs["sd"] == 0 and theirs["ssd_percent"] == 0
        assert ours["esa"] == pytest.approx(0, abs=1e-12) and ours["pds"] == 0
        return
    # swclib measures node to nearest node (nodes every S), we point to nearest segment: the
    # node-to-node distance is longer by up to about S / 2 over a distance >= 1.5 S
    assert ours["esa"] * diag == pytest.approx(theirs["sd"], rel=0.08)
    assert ours["dsa"] * diag == pytest.approx(theirs["ssd"], rel=0.08)
    assert ours["pds"] == pytest.approx(theirs["ssd_percent"], abs=0.08)
