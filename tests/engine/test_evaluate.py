"""End-to-end behaviour of skelcore.evaluate: orchestration, progress, cancel, invariance, errors."""

import math

import numpy as np
import pytest

from skelcore import Cancelled, Params, SkelInputError, evaluate, shapes
from skelcore.curve import CurveSkeleton


@pytest.fixture(scope="module")
def cylinder_eval():
    sh = shapes.cylinder(2500, radius=0.5, length=4.0, seed=7)
    return sh, evaluate(sh.cloud, sh.skeletal, (sh.curve_vertices, sh.curve_edges))


def test_cylinder_with_its_axis_scores_as_the_spec_says(cylinder_eval):
    sh, ev = cylinder_eval
    s = ev.summary()
    inner = (sh.skeletal[:, 2] > 0.4) & (sh.skeletal[:, 2] < 3.6)
    assert np.all(ev.skeletal.boundedness[inner] > 0.75)
    assert s["boundedness"]["curve"] > 0.9
    assert s["centeredness"]["curve"] > 0.9
    assert s["smoothness"]["curve"] == pytest.approx(1.0, abs=1e-9)
    assert s["smoothness"]["skeletal"] > 0.95
    assert 0.6 < s["centeredness"]["skeletal"] < 0.98
    assert s["topology"]["n_bars"] >= 1 and math.isfinite(s["topology"]["bottleneck"])


def test_counts_say_how_many_elements_each_score_counted(cylinder_eval):
    sh, ev = cylinder_eval
    counts = ev.summary()["counts"]
    assert counts["boundedness"]["skeletal"] == len(sh.cloud)
    assert counts["boundedness"]["curve"] == len(ev.curve.samples)
    assert counts["smoothness"]["curve"] == int((ev.curve.vertex_degree == 2).sum())
    assert counts["centeredness"]["curve"] <= len(ev.curve.samples)


def test_local_arrays_have_one_value_per_element(cylinder_eval):
    sh, ev = cylinder_eval
    n = len(sh.cloud)
    for arr in (ev.skeletal.boundedness, ev.skeletal.centeredness_raw, ev.skeletal.smoothness):
        assert arr.shape == (n,)
    m = len(ev.curve.samples)
    assert ev.curve.sample_boundedness.shape == (m,) and ev.curve.sample_centeredness_raw.shape == (m,)
    assert ev.curve.vertex_smoothness.shape == (len(sh.curve_vertices),)
    # samples are written back in the user's units: they lie on the true axis
    assert np.allclose(ev.curve.samples[:, :2], 0, atol=1e-9)
    assert ev.curve.samples[:, 2].max() == pytest.approx(4.0)


def test_thresholds_change_scores_without_recomputing(cylinder_eval):
    _, ev = cylinder_eval
    strict = ev.summary(beta_star=0.99, c_star=0.99)
    loose = ev.summary(beta_star=0.0, c_star=0.0)
    assert strict["boundedness"]["skeletal"] <= ev.summary()["boundedness"]["skeletal"] <= loose["boundedness"]["skeletal"]
    assert strict["centeredness"]["skeletal"] <= loose["centeredness"]["skeletal"]


def test_unbounded_points_get_zero_centeredness():
    sh = shapes.cylinder(1500, seed=3)
    skel = sh.skeletal.copy()
    skel[:50] += [5.0, 0.0, 0.0]  # far outside the cylinder
    ev = evaluate(sh.cloud, skel)
    assert np.all(ev.skeletal.boundedness[:50] < 0.75)
    assert np.all(ev.skeletal.centeredness(0.75)[:50] == 0.0)


def test_without_correspondence_a_cloud_above_coverage_max_points_keeps_every_reason():
    """The skeletal column's reasons (no correspondence) and coverage's (too many points) are
    both reported; the first does not replace the second."""
    sh = shapes.cylinder(400, seed=2)
    ev = evaluate(sh.cloud, sh.skeletal[::8], params=Params(coverage_max_points=100))
    assert ev.correspondence == "none" and len(ev.skeletal.points) == 50
    assert set(ev.not_computed) == {"topology", "skeletal centeredness", "coverage"}
    assert "coverage_max_points = 100" in ev.not_computed["coverage"]
    assert ev.topology is None and ev.coverage_skeletal is None
    assert set(ev.to_json_dict()["not_computed"]) == {"topology", "skeletal centeredness", "coverage"}


def test_junction_vertex_smoothness_is_nan_not_zero():
    sh = shapes.y_shape(3000, seed=1)
    ev = evaluate(sh.cloud, curve=(sh.curve_vertices, sh.curve_edges))
    deg = ev.curve.vertex_degree
    assert np.all(np.isnan(ev.curve.vertex_smoothness[deg != 2]))
    assert np.all(np.isfinite(ev.curve.vertex_smoothness[deg == 2]))


def test_scores_are_invariant_under_translation_and_uniform_scaling():
    sh = shapes.torus(1500, seed=5)
    curve = (sh.curve_vertices, sh.curve_edges)
    a = evaluate(sh.cloud, sh.skeletal, curve)
    moved = lambda x: np.asarray(x) * 37.5 + np.array([1000.0, -20.0, 3.0])  # noqa: E731
    b = evaluate(moved(sh.cloud), moved(sh.skeletal), (moved(sh.curve_vertices), sh.curve_edges))
    np.testing.assert_allclose(a.skeletal.boundedness, b.skeletal.boundedness, atol=1e-6)
    np.testing.assert_allclose(a.skeletal.centeredness_raw, b.skeletal.centeredness_raw, atol=1e-6)
    np.testing.assert_allclose(a.curve.sample_centeredness_raw, b.curve.sample_centeredness_raw, atol=1e-6)
    assert a.topology.bottleneck == pytest.approx(b.topology.bottleneck, rel=1e-6)
    assert a.topology.wasserstein == pytest.approx(b.topology.wasserstein, rel=1e-6)


def test_progress_is_monotonic_and_reaches_one():
    sh = shapes.cylinder(1200, seed=2)
    seen = []
    evaluate(sh.cloud, sh.skeletal, (sh.curve_vertices, sh.curve_edges), progress=lambda f, s: seen.append((f, s)))
    fractions = [f for f, _ in seen]
    assert fractions == sorted(fractions)
    assert fractions[-1] == pytest.approx(1.0)
    assert {"topology", "skeletal boundedness", "curve centeredness"} <= {s for _, s in seen}


def test_cancel_raises_cancelled_at_the_next_checkpoint():
    sh = shapes.cylinder(1200, seed=2)
    calls = {"n": 0}

    def cancel():
        calls["n"] += 1
        return calls["n"] > 3

    with pytest.raises(Cancelled):
        evaluate(sh.cloud, sh.skeletal, (sh.curve_vertices, sh.curve_edges), cancel=cancel)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(cloud=np.zeros((0, 3))), "no points"),
        (dict(cloud=np.ones((10, 3))), "coincide"),
        (dict(cloud=np.array([[0, 0, np.nan], [1, 1, 1]])), "NaN"),
        (dict(cloud=np.random.default_rng(0).random((10, 2))), "N x 3"),
        (dict(cloud=np.random.default_rng(0).random((10, 3)), skeletal=np.zeros((9, 3)), skeletal_index=np.arange(8)),
             "has 8 rows, needs one cloud row per skeletal point"),
            (dict(cloud=np.random.default_rng(0).random((10, 3)), skeletal=np.zeros((9, 3)), skeletal_index=np.arange(9) + 2),
             "cloud row 10 out of range"),
        (dict(cloud=np.random.default_rng(0).random((10, 3)), curve=(np.eye(3), [[0, 3]])), "out of range"),
    ],
)
def test_bad_inputs_raise_one_line_input_errors(kwargs, message):
    with pytest.raises(SkelInputError, match=message) as info:
        evaluate(**kwargs)
    assert "\n" not in str(info.value)


def test_curve_skeleton_object_and_pair_are_equivalent():
    sh = shapes.torus(1200, seed=4)
    c = CurveSkeleton.from_raw(sh.curve_vertices, sh.curve_edges)
    a = evaluate(sh.cloud, curve=c)
    b = evaluate(sh.cloud, curve=(sh.curve_vertices, sh.curve_edges))
    np.testing.assert_array_equal(a.curve.sample_boundedness, b.curve.sample_boundedness)
    assert a.topology is None and a.skeletal is None


def test_paper_estimator_is_selectable_and_named_in_json():
    sh = shapes.cylinder(600, seed=9)
    ev = evaluate(sh.cloud, curve=(sh.curve_vertices, sh.curve_edges), params=Params(boundedness_method="paper"))
    doc = ev.to_json_dict()
    assert doc["params"]["boundedness_estimator"] == "paper"
    assert doc["inputs"]["skeletal"] is None
