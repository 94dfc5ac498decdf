"""The flat scores record (skelcore.scores): the same values as ``Evaluation.summary`` and as the local
arrays counted by hand, NaN kept and told apart from "not computed", thresholds from Params, read back
equal from the ``--json`` document, one column catalogue in row order, and the one number formatter."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

from skelcore import Params, evaluate, shapes
from skelcore.cli.common import format_reference, format_table
from skelcore.compare.jobs import HELD_COLUMNS, SCORE_COLUMNS as RECORD_KEYS, scores_from_doc
from skelcore.compare.leaderboard import COLUMNS as LEADERBOARD_COLUMNS, LOWER_IS_BETTER
from skelcore.compare.results_csv import COLUMNS as RESULTS_COLUMNS
from skelcore.scores import COLUMN, SCORE_COLUMNS, Scores, column_keys, format_score, paired_columns, paper_table

PAPER = [(m, k) for m in ("boundedness", "centeredness", "smoothness") for k in ("skeletal", "curve")]


@pytest.fixture(scope="module")
def evaluations():
    """Generated shapes with known skeletons, in the situations the tables meet: both representations,
    a reference curve, a curve alone, a skeletal set without correspondence, one in another frame."""
    cyl, y = shapes.cylinder(700, seed=3), shapes.y_shape(700, seed=4)
    p = Params(curve_samples=60)
    return {
        "both": evaluate(cyl.cloud, cyl.skeletal, (cyl.curve_vertices, cyl.curve_edges), p),
        "reference": evaluate(y.cloud, y.skeletal, (y.curve_vertices, y.curve_edges), p,
                              reference_curve=(y.curve_vertices[::2], np.array([[0, 1], [1, 2]]))),
        # the reference's facts: its third vertex 3 radii outside the surface (docs/metrics.md 5.3.1)
        "held": evaluate(y.cloud, curve=(y.curve_vertices, y.curve_edges), params=p,
                         reference_curve=(y.curve_vertices[::2], np.array([[0, 1], [1, 2]])),
                         reference_outside=np.r_[0.0, 0.0, 3.0, np.zeros(len(y.curve_vertices[::2]) - 3)]),
        "curve only": evaluate(y.cloud, curve=(y.curve_vertices, y.curve_edges), params=p),
        "no correspondence": evaluate(cyl.cloud, cyl.skeletal[:60], params=p),
        "other frame": evaluate(cyl.cloud, cyl.skeletal * 30 + 100, params=p),
    }


def _nan_equal(a, b) -> bool:
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return a == b


@pytest.mark.parametrize("case", ["both", "reference", "curve only", "no correspondence", "other frame"])
def test_the_record_holds_the_summarys_values(evaluations, case):
    ev = evaluations[case]
    s, summ = ev.scores(), ev.summary()
    topo = summ["topology"] or {}
    assert (s.d_B, s.d_Wp, s.eps_star, s.n_bars) == (topo.get("bottleneck"), topo.get("wasserstein"),
                                                      topo.get("eps_star"), topo.get("n_bars"))
    for metric, kind in PAPER:
        assert _nan_equal(s.get(f"{metric}_{kind}"), summ[metric][kind]), (metric, kind)
        assert s.get(f"n_{metric}_{kind}") == summ["counts"][metric][kind]
    for kind in ("skeletal", "curve"):
        block = (summ["coverage"] or {}).get(kind)
        assert s.get(f"coverage_{kind}") == (None if block is None else block["fraction"])
        assert s.get(f"coverage_{kind}_max_gap") == (None if block is None else block["max_gap"])
    assert s.n_warnings == len(ev.warnings)
    assert s.seconds == round(ev.timings["total"], 6)
    assert (s.reference_f1 is None) == (ev.reference is None)


def test_the_record_counts_the_local_values_as_spec_2_to_4_say(evaluations):
    """Independent of summary(): fractions above the thresholds, the mean smoothness, from the arrays."""
    ev = evaluations["both"]
    s, sk, cv = ev.scores(), ev.skeletal, ev.curve
    assert s.boundedness_skeletal == np.mean(sk.boundedness > 0.75) and s.n_boundedness_skeletal == len(sk.points)
    c = np.where(sk.boundedness > 0.75, sk.centeredness_raw, 0.0)
    assert s.centeredness_skeletal == np.mean(c > 0.75)
    assert s.smoothness_skeletal == pytest.approx(np.nanmean(sk.smoothness))
    c_curve = np.where(cv.sample_boundedness > 0.75, cv.sample_centeredness_raw, 0.0)
    valid = np.isfinite(c_curve)
    assert s.centeredness_curve == np.mean(c_curve[valid] > 0.75) and s.n_centeredness_curve == valid.sum()
    assert s.boundedness_curve == np.mean(cv.sample_boundedness > 0.75)


def test_not_computed_is_none_and_no_valid_element_is_nan(evaluations):
    ev = evaluations["no correspondence"]
    s = ev.scores()
    # no correspondence: topology and skeletal centeredness are not computed; no curve was given
    assert s.d_B is None and s.centeredness_skeletal is None and s.boundedness_curve is None
    assert s.boundedness_skeletal is not None
    # every smoothness value invalid: computed, but over no valid element -> NaN with n = 0
    nan_ev = dataclasses.replace(ev, skeletal=dataclasses.replace(ev.skeletal, smoothness=np.full(60, np.nan)))
    s = nan_ev.scores()
    assert math.isnan(s.smoothness_skeletal) and s.n_smoothness_skeletal == 0
    back = Scores.from_json_dict(json.loads(json.dumps(nan_ev.to_json_dict())))
    assert math.isnan(back.smoothness_skeletal) and back.centeredness_skeletal is None and back.d_B is None
    assert back == s
    assert format_table(s).splitlines()[5].split()[:2] == ["smoothness", "nan"]


def test_thresholds_come_from_params_unless_given(evaluations):
    base = evaluations["both"]
    ev = dataclasses.replace(base, params=base.params.replace(beta_star=0.5, c_star=0.9))
    s = ev.scores()
    assert (s.beta_star, s.c_star) == (0.5, 0.9)
    sk = ev.skeletal
    assert s.boundedness_skeletal == np.mean(sk.boundedness > 0.5)
    assert s.centeredness_skeletal == np.mean(np.where(sk.boundedness > 0.5, sk.centeredness_raw, 0.0) > 0.9)
    given = ev.scores(0.2, 0.3)
    assert (given.beta_star, given.c_star) == (0.2, 0.3)
    assert given.centeredness_skeletal == ev.summary(0.2, 0.3)["centeredness"]["skeletal"]
    assert given.centeredness_skeletal != s.centeredness_skeletal
    # the document carries its params' thresholds, and the record read back says so
    assert Scores.from_json_dict(ev.to_json_dict()) == s


@pytest.mark.parametrize("case", ["both", "reference", "curve only", "no correspondence", "other frame"])
def test_the_json_document_reads_back_into_an_equal_record(evaluations, case):
    ev = evaluations[case]
    assert Scores.from_json_dict(ev.to_json_dict()) == ev.scores()
    assert Scores.from_json_dict(json.loads(json.dumps(ev.to_json_dict()))) == ev.scores()


def test_the_compare_record_is_the_flat_record(evaluations):
    for ev in evaluations.values():
        doc = ev.to_json_dict()
        flat = scores_from_doc(doc)
        held = ev.ground_truth is not None and ev.ground_truth.held_f1 is not None
        assert list(flat) == [k for k in RECORD_KEYS if held or k not in HELD_COLUMNS]  # held: only with facts
        want = ev.scores()
        for k, v in flat.items():
            w = want.get(k)
            assert (math.isnan(v) and w is None) or _nan_equal(v, float(w)), k
    assert all(math.isnan(v) for v in scores_from_doc(None).values()) and not set(scores_from_doc(None)) & set(HELD_COLUMNS)
    held = scores_from_doc(evaluations["held"].to_json_dict())
    assert 0 < held["gt_held_f1"] <= 1 and held["gt_held_f1"] != held["gt_f1"]


def test_held_scores_are_none_without_facts_and_read_back_with_them(evaluations):
    """None (not computed) without the reference's facts, NaN never invented; with them, the ground
    truth's own values, the same read back from the JSON document."""
    for name in ("reference", "curve only"):
        s = evaluations[name].scores()
        assert all(s.get(k) is None for k in HELD_COLUMNS), name
    ev = evaluations["held"]
    s, gt = ev.scores(), ev.ground_truth
    assert (s.gt_held_precision, s.gt_held_recall, s.gt_held_f1) == (gt.held_precision, gt.held_recall, gt.held_f1)
    assert Scores.from_json_dict(json.loads(json.dumps(ev.to_json_dict()))) == s
    assert gt.held_nodes == (2, 3) and gt.held_f1 != gt.f1  # the reference's third vertex left out


def test_public_column_lists_stay_as_they_were():
    """results.csv, the job records and the leaderboard keep their columns (public formats), with
    the diagnostics' columns and results.csv's sound / defects / warnings, and the ground-truth
    block beside the paper's (the held scores beside the plain F1); nothing moves."""
    ground_truth = ("gt_chamfer_radii", "gt_chamfer", "gt_precision", "gt_recall", "gt_f1", "gt_held_precision",
                    "gt_held_recall", "gt_held_f1", "gt_junction_precision",
                    "gt_junction_recall", "gt_endpoint_precision", "gt_endpoint_recall", "gt_cycle_error",
                    "gt_length_ratio", "gt_splits", "gt_merges")
    diagnostics = ("completeness_skeletal", "completeness_curve", "spurious_branches", "spurious_cycles",
                   "missing_cycles", "outside_length_share")
    record = ("d_B", "d_Wp", "boundedness_skeletal", "boundedness_curve", "centeredness_skeletal",
              "centeredness_curve", "smoothness_skeletal", "smoothness_curve", *ground_truth, "coverage_skeletal",
              "coverage_curve", *diagnostics, "n_warnings")
    assert RECORD_KEYS == record
    assert LEADERBOARD_COLUMNS == (*record, "seconds")
    assert RESULTS_COLUMNS == ("shape", "method", "condition", "seed", "status", "error", *record, "seconds",
                               "sound", "defects", "warnings", "label", "n_points", "key")
    assert LOWER_IS_BETTER == {"d_B", "d_Wp", "spurious_branches", "spurious_cycles", "missing_cycles",
                               "outside_length_share", "n_warnings", "seconds", "gt_chamfer_radii", "gt_chamfer",
                               "gt_cycle_error", "gt_splits", "gt_merges"}


def test_row_follows_the_column_catalogue(evaluations):
    s = evaluations["reference"].scores()
    keys = [c.key for c in SCORE_COLUMNS]
    assert len(set(keys)) == len(keys)
    assert s.row() == tuple(getattr(s, k) for k in keys)
    fields = {f.name for f in dataclasses.fields(Scores)}
    for c in SCORE_COLUMNS:
        assert c.key in fields and c.better in ("higher", "lower", None) and c.digits >= 0
        assert c.count is None or c.count in fields
        assert c.group in ("paper", "skelscope", "diagnostics", "reference", "ground truth", "run")
    assert [m for m, _s, _c in paired_columns("paper")] == ["boundedness", "centeredness", "smoothness"]
    assert column_keys(group="paper", compared=True)[:2] == ("d_B", "d_Wp")


def test_format_score_edge_cases():
    assert format_score(None) == "-" and format_score(None, missing="—") == "—"
    assert format_score(math.nan) == "nan" and format_score(np.float32("nan"), nan="-") == "-"
    assert format_score(math.inf) == "inf" and format_score(-math.inf, 4) == "-inf"
    assert format_score(0.81249) == "0.812" and format_score(0.0123456, 4) == "0.0123"
    assert format_score(np.float32(0.5)) == "0.500" and format_score(46, 0) == "46" and format_score(True, 0) == "1"
    assert format_score(0.0123, 4, signed=True) == "+0.0123" and format_score(-0.5, 1, signed=True) == "-0.5"
    assert format_score(0.0, 3, signed=True) == "+0.000"
    assert COLUMN["d_B"].format(0.123456) == "0.1235" and COLUMN["eps_star"].format(0.0611155) == "0.06112"


def test_the_papers_table_text_from_a_hand_made_record():
    s = Scores(d_B=0.0123, d_Wp=0.00456, eps_star=0.02, n_bars=7, boundedness_skeletal=0.9, boundedness_curve=1.0,
               centeredness_skeletal=0.85, centeredness_curve=math.nan, smoothness_skeletal=0.7,
               n_boundedness_skeletal=100, n_boundedness_curve=200, n_centeredness_skeletal=100,
               n_smoothness_skeletal=98)
    assert format_table(s).splitlines() == [
        "metric        skeletal points  curve skeleton",
        "------------  ---------------  --------------",
        "d_B / d_Wp    0.0123 / 0.0046  -",
        "boundedness   0.900 (n=100)    1.000 (n=200)",
        "centeredness  0.850 (n=100)    nan (n=0)",
        "smoothness    0.700 (n=98)     -",
        "(eps* = 0.02000, K = 7 bars compared)",
    ]
    covered = dataclasses.replace(s, coverage_curve=0.5, coverage_curve_mean_gap=0.01, coverage_curve_max_gap=0.2,
                                  coverage_slack=0.5, coverage_tau=0.03)
    rows = paper_table(covered, missing="—", sep="  ", count="n = {}")
    assert rows[-1] == ("coverage*", "—", "0.500  (gap 0.0100 / 0.2000)") and rows[1][1] == "0.900  (n = 100)"
    assert "coverage*" not in format_table(s) and "tau = 0.0300" in format_table(covered)
    # a summary() dict gives the same table as the record made from it
    assert format_table(Scores.from_json_dict({"topology": {"bottleneck": 0.0123, "wasserstein": 0.00456,
                                                            "eps_star": 0.02, "n_bars": 7}})).splitlines()[2] == \
        "d_B / d_Wp    0.0123 / 0.0046  -"


def test_reference_lines_from_the_record_or_the_json_block(evaluations):
    ev = evaluations["reference"]
    text = format_reference(ev.scores())
    assert text == format_reference(ev.reference.to_dict())
    assert text.startswith(f"reference curve: chamfer {ev.reference.chamfer:.4f}, ")
    assert "junctions 1/" in text and f"F1 {ev.reference.f1:.3f}" in text


def test_records_compare_with_nan_equal_to_nan():
    a, b = Scores(d_B=math.nan), Scores(d_B=float("nan"))
    assert a == b and hash(a) == hash(b)
    assert a != Scores() and Scores(d_B=0.1) != Scores(d_B=0.2)
    assert Scores().flat(["d_B", "n_warnings"]) == {"d_B": pytest.approx(math.nan, nan_ok=True),
                                                    "n_warnings": pytest.approx(math.nan, nan_ok=True)}
