"""The ground-truth metrics as a stage of ``evaluate`` (docs/metrics.md 5.3.1): a known answer
(a cylinder's axis against the axis moved by a fifth of the radius), the radius from the reference, from
``reference_radius=``, from the cloud or from both, the Scores' "ground truth" columns, what is not
computed, and the CLI's "ground truth" block and JSON document."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

from skelcore import evaluate, shapes
from skelcore.cli import main
from skelcore.curve import CurveSkeleton
from skelcore.errors import SkelInputError
from skelcore.io import write_curve_ply, write_points_ply
from skelcore.metrics.ground_truth import GroundTruthParams, compare_with_ground_truth
from skelcore.params import Params
from skelcore.scores import Scores, column_keys

R, SHIFT = 0.5, 0.1


def _same(a, b) -> bool:
    """Equal results, NaN equal to NaN."""
    return json.dumps(a.to_dict()) == json.dumps(b.to_dict())


@pytest.fixture(scope="module")
def cylinder():
    sh = shapes.cylinder(1500, radius=R, seed=2)
    axis = CurveSkeleton.from_raw(sh.curve_vertices, sh.curve_edges)
    moved = CurveSkeleton.from_raw(sh.curve_vertices + [SHIFT, 0, 0], sh.curve_edges,
                                   radius=np.full(len(sh.curve_vertices), R))
    return sh, axis, moved


def test_a_moved_axis_scores_as_computed_by_hand(cylinder):
    """Every point of one axis is SHIFT = 0.2 r from the other: chamfer SHIFT both ways, 0.2 radii;
    within the thresholds 0.2, 0.25, .., 1 radii (17 of 20): P = R = F1 = 0.85; the same graph."""
    sh, axis, moved = cylinder
    ev = evaluate(sh.cloud, None, axis, reference_curve=moved)
    g = ev.ground_truth
    assert g.radius_source == "reference" and "ground truth" in ev.timings
    assert g.chamfer_to_reference == pytest.approx(SHIFT) and g.chamfer_from_reference == pytest.approx(SHIFT)
    assert g.chamfer_radii == pytest.approx(SHIFT / R)
    assert (g.precision, g.recall, g.f1) == pytest.approx((0.85, 0.85, 0.85))
    assert g.endpoints == (2, 2, 2) and g.junctions == (0, 0, 0) and g.cycle_error == 0
    assert g.length_ratio == pytest.approx(1.0) and (g.splits, g.merges) == (0, 0)
    s = ev.scores()
    assert (s.gt_chamfer, s.gt_chamfer_radii, s.gt_f1) == pytest.approx((SHIFT, SHIFT / R, 0.85))
    assert s.gt_radius_source == "reference" and s.gt_endpoints == (2, 2, 2)
    assert Scores.from_json_dict(json.loads(json.dumps(ev.to_json_dict()))) == s


def test_the_stage_gives_what_the_metric_gives(cylinder):
    """The stage is compare_with_ground_truth on the user's inputs with the Params' gt_ constants."""
    sh, axis, moved = cylinder
    p = Params(gt_thresholds=7, gt_match_radii=1.5)
    ev = evaluate(sh.cloud, None, axis, p, reference_curve=moved)
    direct = compare_with_ground_truth(axis, moved, moved.radius, params=GroundTruthParams(thresholds=7, match_radii=1.5))
    assert _same(ev.ground_truth, direct) and len(ev.ground_truth.thresholds) == 7


def test_the_radius_from_the_cloud_from_the_argument_or_from_both(cylinder):
    sh, axis, moved = cylinder
    bare = dataclasses.replace(moved, radius=None)
    from_cloud = evaluate(sh.cloud, None, axis, reference_curve=bare).ground_truth
    assert _same(from_cloud, compare_with_ground_truth(axis, bare, None, sh.cloud))
    assert from_cloud.radius_source == "cloud"
    # the cloud's estimate at (0.1, 0, z) is about the distance to the nearest wall, 0.4, not 0.5
    assert 0.2 < from_cloud.chamfer_radii < 0.3
    doubled = evaluate(sh.cloud, None, axis, reference_curve=moved, reference_radius=np.full(moved.n_vertices, 2 * R))
    assert doubled.ground_truth.radius_source == "reference"
    assert doubled.ground_truth.chamfer_radii == pytest.approx(SHIFT / (2 * R))
    partial = np.full(moved.n_vertices, R)
    partial[:5] = np.nan
    both = evaluate(sh.cloud, None, axis, reference_curve=moved, reference_radius=partial).ground_truth
    assert both.radius_source == "reference+cloud"
    assert from_cloud.chamfer_radii > both.chamfer_radii > SHIFT / R
    # a (vertices, edges) pair with a NaN vertex: the radius given per raw vertex follows the cleaning
    v = np.vstack([[np.nan] * 3, moved.vertices])
    with pytest.warns(UserWarning, match="NaN"):
        raw = evaluate(sh.cloud, None, axis, reference_curve=(v, moved.edges + 1),
                       reference_radius=np.full(len(v), R)).ground_truth
    assert raw.chamfer_radii == pytest.approx(SHIFT / R)


def test_without_a_usable_reference_nothing_is_made_up(cylinder):
    sh, axis, moved = cylinder
    ev = evaluate(sh.cloud, None, axis)
    assert ev.ground_truth is None and "ground truth" not in ev.timings
    assert all(ev.scores().get(k) is None for k in column_keys(group="ground truth"))
    assert ev.to_json_dict()["ground_truth"] is None
    dots = evaluate(sh.cloud, None, axis, reference_curve=(moved.vertices, np.empty((0, 2))))
    assert dots.ground_truth is None and dots.reference is not None
    assert dots.not_computed["ground truth"] == "the reference curve has no edges"
    with pytest.raises(SkelInputError, match="reference radius needs a reference curve"):
        evaluate(sh.cloud, None, axis, reference_radius=np.ones(3))
    with pytest.raises(SkelInputError, match="reference radius: 3 values for a reference curve of 21 vertices"):
        evaluate(sh.cloud, None, axis, reference_curve=moved, reference_radius=np.ones(3))


def test_the_cycle_error_column_is_its_size(cylinder):
    """A ring against the open axis: one cycle too many, |cycle count error| 1 (the document keeps its sign)."""
    sh, axis, moved = cylinder
    ring = CurveSkeleton.from_raw(moved.vertices, np.vstack([moved.edges, [[0, moved.n_vertices - 1]]]),
                                  radius=moved.radius)
    ev = evaluate(sh.cloud, None, axis, reference_curve=ring)
    assert ev.to_json_dict()["ground_truth"]["cycle_error"] == -1 and ev.scores().gt_cycle_error == 1
    assert ev.ground_truth.endpoints == (2, 0, 0) and math.isnan(ev.ground_truth.endpoint_precision) is False
    assert ev.ground_truth.endpoint_precision == 0.0 and math.isnan(ev.ground_truth.endpoint_recall)


def test_the_cli_prints_the_ground_truth_block_and_writes_it(cylinder, tmp_path, capsys):
    sh, axis, moved = cylinder
    write_points_ply(tmp_path / "cloud.ply", sh.cloud)
    write_curve_ply(tmp_path / "curve.ply", axis.vertices, axis.edges)
    write_curve_ply(tmp_path / "ref.ply", moved.vertices, moved.edges, scalars={"radius": moved.radius})
    write_curve_ply(tmp_path / "bare.ply", moved.vertices, moved.edges)
    assert main(["evaluate", str(tmp_path / "cloud.ply"), "--curve", str(tmp_path / "curve.ply"), "--reference-curve",
                 str(tmp_path / "ref.ply"), "--json", str(tmp_path / "ev.json"), "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "ground truth (local radius r: the reference's file):" in out
    assert "chamfer 0.1000 = 0.200 r" in out and "precision 0.850, recall 0.850, F1 0.850" in out
    assert "endpoints P 1.000 R 1.000 (ours 2, reference 2, matched 2)" in out
    assert out.index("ground truth") > out.index("smoothness")  # under the paper's table
    doc = json.loads((tmp_path / "ev.json").read_text())
    assert doc["ground_truth"]["radius_source"] == "reference" and doc["ground_truth"]["f1"] == pytest.approx(0.85)
    assert main(["evaluate", str(tmp_path / "cloud.ply"), "--curve", str(tmp_path / "curve.ply"), "--reference-curve",
                 str(tmp_path / "bare.ply"), "--quiet"]) == 0
    assert "ground truth (local radius r: estimated from the cloud):" in capsys.readouterr().out
