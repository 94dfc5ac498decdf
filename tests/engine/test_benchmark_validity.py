"""``skelcore bench validity``: the controlled defects, the statistics, and a small
run on the pool with its outputs, resume and bad --out."""

from __future__ import annotations

import csv
import json
import math
import os

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from skelcore.benchmark import skeleton_defects as sd
from skelcore.benchmark.validity import _shape
from skelcore.benchmark.validity_stats import auc, blind_spots, is_blind, spearman, validity_table
from skelcore.benchmark.tubes import signed_distance
from skelcore.cli.main import main


def _cycle_rank(v: np.ndarray, e: np.ndarray) -> int:
    n = len(v)
    c = connected_components(coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n)), directed=False)[0]
    return int(len(e) - n + c)


def _length(v: np.ndarray, e: np.ndarray) -> float:
    return float(np.linalg.norm(v[e[:, 1]] - v[e[:, 0]], axis=1).sum())


def _path(n: int = 101, length: float = 10.0):
    v = np.column_stack([np.linspace(0, length, n), np.zeros(n), np.zeros(n)])
    return v, np.column_stack([np.arange(n - 1), np.arange(1, n)]), np.full(n, 0.5)


def test_truncation_cuts_each_end_by_its_share_of_the_branch():
    v, e, _ = _path()
    tv, te = sd.truncate(v, e, 0.2)
    # both free ends of the path (one branch of length 10) lose 2 units: 6 left, up to one vertex step
    assert abs(_length(tv, te) - 6.0) <= 0.1 + 1e-9
    assert tv[:, 0].min() >= 2.0 - 1e-9 and tv[:, 0].max() <= 8.0 + 1e-9
    torus_v = np.column_stack([np.cos(np.linspace(0, 2 * np.pi, 40, endpoint=False)),
                               np.sin(np.linspace(0, 2 * np.pi, 40, endpoint=False)), np.zeros(40)])
    ring = np.column_stack([np.arange(40), (np.arange(40) + 1) % 40])
    assert sd.truncate(torus_v, ring, 0.2) is None  # no free end: does not apply


def test_graph_defects_change_the_topology_as_named():
    _, _, (v, e, r) = _shape("junction_y", 0)
    rng = np.random.default_rng(3)
    deg = np.bincount(e.ravel())
    # missing branch: one terminal branch gone, the junction now of degree 2
    mv, me = sd.drop_branches(v, e, 1, rng)
    assert (np.bincount(me.ravel()) == 1).sum() == 2 and (np.bincount(me.ravel()) >= 3).sum() == 0
    assert sd.drop_branches(v, e, 3, rng) is None  # a Y has three limbs: removing all is not this defect
    # chord: one more cycle; shortcuts: one more cycle each, through the air
    assert _cycle_rank(*sd.add_chord(v, e, r, 2.0, rng)) == 1
    surface = lambda p: signed_distance(_shape("junction_y", 0)[0], p, spacing=0.1)  # noqa: E731
    sv, se = sd.add_shortcuts(v, e, r, 2, rng, surface)
    assert _cycle_rank(sv, se) == 2
    new = sv[len(v):]
    assert (signed_distance(_shape("junction_y", 0)[0], new) > 0).any()
    # spurs: k new free ends, each hung sideways
    pv, pe, tips = sd.add_spurs(v, e, r, 3, 2.0, rng)
    assert (np.bincount(pe.ravel()) == 1).sum() == (deg == 1).sum() + 3 and len(tips) == 3


def test_broken_cycle_opens_the_torus_by_the_gap_and_oversmoothing_shrinks_it():
    _, _, (v, e, r) = _shape("torus", 0)
    assert _cycle_rank(v, e) == 1
    bv, be = sd.break_cycle(v, e, r, 8.0, np.random.default_rng(0))
    assert _cycle_rank(bv, be) == 0
    gap = _length(v, e) - _length(bv, be)
    assert 6.0 * r.min() <= gap <= 9.0 * r.max()
    sv, _ = sd.oversmooth(v, e, 1000)
    centre = v.mean(axis=0)
    assert np.linalg.norm(sv - centre, axis=1).mean() < 0.9 * np.linalg.norm(v - centre, axis=1).mean()
    # a tree: ends and junctions stay where they are
    _, _, (tv, te, _) = _shape("junction_y", 0)
    ov, _ = sd.oversmooth(tv, te, 100)
    fixed = np.bincount(te.ravel()) != 2
    assert np.array_equal(ov[fixed], tv[fixed])


def test_offset_and_noise_are_in_local_radii_and_deterministic():
    _, _, (v, e, r) = _shape("tube_a", 0)
    ov, _ = sd.offset(v, e, r, 0.5, np.random.default_rng(1))
    assert np.allclose(np.linalg.norm(ov - v, axis=1), 0.5 * r)
    a = sd.apply_defect("noise", 0.25, v, e, r, np.random.default_rng(7), None)
    b = sd.apply_defect("noise", 0.25, v, e, r, np.random.default_rng(7), None)
    assert np.array_equal(a[0], b[0])
    assert 0.15 < np.std((a[0] - v) / r[:, None]) < 0.35


def test_auc_and_spearman_against_their_definitions():
    rng = np.random.default_rng(0)
    x, y = rng.normal(size=30), rng.normal(size=25) + 0.5
    pairs = (x[:, None] > y[None, :]).mean() + 0.5 * (x[:, None] == y[None, :]).mean()
    assert math.isclose(auc(x, y), pairs)
    assert auc(np.array([1.0, 1.0]), np.array([1.0, 1.0])) == 0.5
    assert math.isnan(auc(np.array([1.0]), np.array([0.0, 1.0])))
    u = rng.normal(size=40)
    assert math.isclose(spearman(u, np.exp(u)), 1.0)
    assert math.isclose(spearman(u, -u ** 3), -1.0)
    assert math.isnan(spearman(u, np.ones(40)))
    stats = pytest.importorskip("scipy.stats")
    a, b = rng.integers(0, 4, 50).astype(float), rng.integers(0, 6, 50).astype(float)  # ties
    assert math.isclose(spearman(a, b), stats.spearmanr(a, b)[0], abs_tol=1e-12)


def _ranks_auc(a, b):
    """The study's former own code (average ranks, Mann-Whitney U): the library call must equal it."""
    x = np.concatenate([a, b])
    _, inv, counts = np.unique(x, return_inverse=True, return_counts=True)
    ranks = (np.cumsum(counts) - (counts - 1) / 2.0)[inv]
    return (ranks[: len(a)].sum() - len(a) * (len(a) + 1) / 2) / (len(a) * len(b))


def test_auc_is_sklearns_roc_auc_and_the_former_rank_formula():
    metrics = pytest.importorskip("sklearn.metrics")
    rng = np.random.default_rng(4)
    for _ in range(5):
        a, b = rng.integers(0, 5, 23).astype(float), rng.integers(0, 4, 17).astype(float)  # many ties
        want = metrics.roc_auc_score(np.r_[np.ones(23), np.zeros(17)], np.r_[a, b])
        assert math.isclose(auc(a, b), want, abs_tol=1e-12) and math.isclose(auc(a, b), _ranks_auc(a, b), abs_tol=1e-12)


def _rows(effect: float, noise: float, shapes: int = 8, seed: int = 0):
    """Clean rows with a wide spread between shapes; each defective level adds ``effect`` x level."""
    rng = np.random.default_rng(seed)
    rows = []
    for k in range(shapes):
        base = 10.0 * rng.normal()
        rows.append({"shape": f"s{k}", "seed": 0, "defect": "clean", "level": "", "level_index": 0, "d_B": base,
                     "gt_error": 0.0})
        for lv in (1, 2, 3):
            rows.append({"shape": f"s{k}", "seed": 0, "defect": "spurs", "level": str(lv), "level_index": lv,
                         "d_B": base + effect * lv + noise * rng.normal(), "gt_error": 0.1 * lv})
    return rows


def test_pairing_sees_what_pooling_hides_and_blind_needs_the_interval():
    from skelcore.benchmark.validity_stats import METRICS

    d_b = tuple(m for m in METRICS if m.key == "d_B")
    # a small shift against a large spread between shapes: pooled AUC near 0.5, every pair worse
    rec = validity_table(_rows(0.5, 0.01), d_b)[0]
    assert rec["auc"] < 0.7 and rec["auc_paired"] == 1.0 and rec["auc_paired_ci"] == (1.0, 1.0)
    assert rec["n_pairs"] == 24 and math.isclose(rec["effect"], 1.0, abs_tol=0.01)
    assert rec["effect_ci"][0] > 0.9 and rec["wilcoxon_p"] < 1e-4
    assert not is_blind(rec)
    # no effect, only noise: the paired interval holds 0.5, so blind
    rec = validity_table(_rows(0.0, 1.0), d_b)[0]
    assert rec["auc_paired_ci"][0] <= 0.5 <= rec["auc_paired_ci"][1] and is_blind(rec)
    assert blind_spots([{**rec, "group": "paper"}]) == {"d_B": ["spurs"]}


ARGS = ["bench", "validity", "--suite", "small", "--shapes", "junction_y", "tube_a", "--defects", "truncation",
        "spurs", "--seeds", "1", "--points", "600", "--backend", "pool", "--workers", "2", "--quiet"]


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    out = tmp_path_factory.mktemp("validity") / "run"
    assert main([*ARGS, "--out", str(out)]) == 0
    return out


def _table(out):
    with open(out / "validity.csv") as fh:
        return list(csv.DictReader(fh))


def test_ground_truth_f1_sees_truncation_and_boundedness_does_not(run):
    table = {(r["metric"], r["defect"]): r for r in _table(run)}
    assert float(table[("gt_f1", "truncation")]["auc"]) > 0.9
    assert float(table[("gt_f1", "spurs")]["auc"]) > 0.9
    # the exact skeleton cut short stays inside the shape: every sample bounded, as on the clean one
    with open(run / "scores.csv") as fh:
        rows = list(csv.DictReader(fh))
    trunc = [r for r in rows if r["defect"] in ("truncation", "clean")]
    assert trunc and all(float(r["boundedness_curve"]) == 1.0 for r in trunc)
    assert float(table[("boundedness_curve", "truncation")]["auc"]) == 0.5
    stats = [{"metric": r["metric"], "group": r["group"], "defect": r["defect"], "auc": float(r["auc"])}
             for r in _table(run)]
    assert "truncation" in blind_spots(stats)["boundedness_curve"]
    md = (run / "validity.md").read_text()
    assert "- boundedness (curve): truncation" in md


def test_outputs_exist_and_parse(run):
    with open(run / "scores.csv") as fh:
        rows = list(csv.DictReader(fh))
    # 2 shapes x 1 seed x (clean + 3 truncations + 3 spur levels)
    assert len(rows) == 14
    assert {r["defect"] for r in rows} == {"clean", "truncation", "spurs"}
    assert all(0.0 <= float(r["gt_f1"]) <= 1.0 for r in rows)
    clean = [r for r in rows if r["defect"] == "clean"]
    assert all(float(r["gt_f1"]) == pytest.approx(1.0) for r in clean)
    table = _table(run)
    assert {r["defect"] for r in table} == {"truncation", "spurs"}
    assert all(len(r["auc_levels"].split()) == 3 for r in table)
    md = (run / "validity.md").read_text()
    assert "| metric | group | truncation | spurs |" in md
    mpimg = pytest.importorskip("matplotlib.image")
    img = mpimg.imread(run / "validity.png")
    assert img.ndim == 3 and img.shape[0] > 200 and img.shape[1] > 200
    marker = json.loads((run / ".skelscope-run").read_text())
    assert marker["kind"] == "validity"


def test_resume_does_not_recompute(run, capsys):
    tasks = sorted((run / "tasks").glob("*.json"))
    before = {p.name: os.stat(p).st_mtime_ns for p in tasks}
    assert len(tasks) == 6
    capsys.readouterr()
    assert main([*ARGS, "--out", str(run), "--no-figure"]) == 0
    out = capsys.readouterr().out
    assert "6 tasks: 6 already done, 0 ran, 0 failed; 14 scored skeletons" in out
    # the blind spots printed are those of the table written (validity.csv), every metric's
    stats = [{"metric": r["metric"], "group": r["group"], "defect": r["defect"], "auc": float(r["auc"])}
             for r in _table(run)]
    for metric, blind in blind_spots(stats).items():
        assert f"shapes {metric}: blind to {', '.join(blind) if blind else 'none'}\n" in out, metric
    assert {p.name: os.stat(p).st_mtime_ns for p in sorted((run / "tasks").glob("*.json"))} == before


@pytest.mark.parametrize("kind", ["file", "user_folder", "other_run"])
def test_bad_out_is_one_line_exit_2(tmp_path, capsys, kind):
    out = tmp_path / "out"
    if kind == "file":
        out.write_text("mine")
    elif kind == "user_folder":
        out.mkdir()
        (out / "notes.txt").write_text("mine")
    else:
        out.mkdir()
        (out / ".skelscope-run").write_text(json.dumps({"skelscope_run": 1, "kind": "compare"}))
    capsys.readouterr()
    assert main(["bench", "validity", "--out", str(out), "--suite", "small", "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(out) in err[0] and err[0].startswith("skelcore: error:")
    if kind == "file":
        assert out.read_text() == "mine"
    elif kind == "user_folder":
        assert sorted(os.listdir(out)) == ["notes.txt"]


def test_unknown_defect_or_shape_is_one_line_exit_2(tmp_path, capsys):
    for extra in (["--defects", "wobble"], ["--shapes", "plate"]):
        capsys.readouterr()
        assert main(["bench", "validity", "--out", str(tmp_path / "o"), "--suite", "small", *extra]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and ("wobble" in err[0] or "plate" in err[0])
    assert not (tmp_path / "o").exists()
