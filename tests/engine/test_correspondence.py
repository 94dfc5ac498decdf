"""Skeletal sets without pointwise correspondence: index, reverse projection (onto points and onto a
curve's edges), the no-correspondence fallback, and the JSON ``correspondence`` field."""

import numpy as np
import pytest

from skelcore import evaluate, shapes
from skelcore.correspondence import aggregate_rows, project_onto_curve, reverse_projection
from skelcore.curve import CurveSkeleton
from skelcore.errors import SkelInputError


def _brute_curve_distance(points, curve):
    v, e = curve.vertices, curve.edges
    a, b = v[e[:, 0]], v[e[:, 1]]
    d = b - a
    t = np.clip(np.einsum("pij,ij->pi", points[:, None] - a[None], d) / np.einsum("ij,ij->i", d, d), 0, 1)
    q = a[None] + t[..., None] * d[None]
    best = np.linalg.norm(q - points[:, None], axis=2).min(axis=1)
    iso = np.setdiff1d(np.arange(len(v)), e.ravel())
    if len(iso):
        best = np.minimum(best, np.linalg.norm(points[:, None] - v[iso][None], axis=2).min(axis=1))
    return best


def test_projection_onto_curve_matches_brute_force():
    rng = np.random.default_rng(3)
    v = rng.normal(size=(41, 3))
    e = np.array([[i, i + 1] for i in range(37)] + [[0, 20], [5, 30]])  # vertices 38..40 isolated
    curve = CurveSkeleton.from_raw(v, e)
    cloud = rng.normal(size=(2500, 3)) * 1.5
    q, edge = project_onto_curve(cloud, curve)
    assert np.allclose(np.linalg.norm(q - cloud, axis=1), _brute_curve_distance(cloud, curve), atol=1e-12)
    on_edge = edge >= 0
    ee = curve.edges[edge[on_edge]]
    a, b = curve.vertices[ee[:, 0]], curve.vertices[ee[:, 1]]
    # every projection lies on the edge it names
    cross = np.linalg.norm(np.cross(q[on_edge] - a, b - a), axis=1) / np.linalg.norm(b - a, axis=1)
    assert cross.max() < 1e-9


def test_reverse_projection_and_aggregation():
    skel = np.array([[0.0, 0, 0], [10, 0, 0], [20, 0, 0]])
    cloud = np.array([[1.0, 0, 0], [9, 0, 0], [11, 0, 0], [-3, 0, 0]])
    rows = reverse_projection(cloud, skel)
    assert rows.tolist() == [0, 1, 1, 0]
    agg = aggregate_rows(np.array([0.2, 0.4, np.nan, 0.6]), rows, 3)
    assert agg[0] == pytest.approx(0.4) and agg[1] == pytest.approx(0.4) and np.isnan(agg[2])


def test_reverse_on_the_full_pointwise_set_changes_nothing():
    # every cloud row's nearest skeletal point is its own: the skeletal set is a copy of the cloud
    # moved by far less than the point spacing
    sh = shapes.cylinder(800, seed=4)
    skel = sh.cloud + np.random.default_rng(1).normal(scale=1e-7, size=sh.cloud.shape)
    a = evaluate(sh.cloud, skel)
    b = evaluate(sh.cloud, skel, correspondence="reverse")
    assert a.correspondence == "pointwise" and b.correspondence == "reverse"
    assert np.array_equal(b.skeletal.rows, np.arange(len(skel)))
    assert b.summary()["centeredness"]["skeletal"] == pytest.approx(a.summary()["centeredness"]["skeletal"])
    assert b.topology.bottleneck == pytest.approx(a.topology.bottleneck)


def test_subsampled_skeleton_scored_by_reverse_projection_is_close_to_the_full_set():
    sh = shapes.y_shape(3000, seed=5)
    full = evaluate(sh.cloud, sh.skeletal)
    rng = np.random.default_rng(0)
    sub = sh.skeletal[rng.choice(len(sh.skeletal), 300, replace=False)]
    rev = evaluate(sh.cloud, sub, correspondence="reverse")
    s_full, s_rev = full.summary(), rev.summary()
    assert s_rev["counts"]["centeredness"]["skeletal"] == len(sh.cloud)  # counted per cloud row
    assert abs(s_rev["centeredness"]["skeletal"] - s_full["centeredness"]["skeletal"]) < 0.15
    assert len(rev.skeletal.centeredness_raw) == 300  # local values stay one per skeletal point
    assert rev.to_json_dict()["correspondence"] == "reverse"


def test_index_correspondence_uses_the_given_rows():
    sh = shapes.cylinder(1000, seed=6)
    rows = np.arange(0, 1000, 4)
    ev = evaluate(sh.cloud, sh.skeletal[rows], skeletal_index=rows)
    assert ev.correspondence == "index"
    ref = evaluate(sh.cloud[rows], sh.skeletal[rows])
    assert np.allclose(ev.skeletal.centeredness_raw, ref.skeletal.centeredness_raw, equal_nan=True)


def test_counts_differ_without_correspondence_gives_null_with_reason_and_one_warning():
    sh = shapes.cylinder(1000, seed=7)
    ev = evaluate(sh.cloud, sh.skeletal[:200])
    doc = ev.to_json_dict()
    assert doc["correspondence"] == "none"
    assert doc["topology"] is None and doc["centeredness"]["skeletal"] is None
    assert doc["boundedness"]["skeletal"] is not None and doc["smoothness"]["skeletal"] is not None
    assert "topology" in doc["not_computed"] and "skeletal centeredness" in doc["not_computed"]
    codes = [w["code"] for w in doc["warnings"]]
    assert codes.count("no_correspondence") == 1
    msg = doc["warnings"][codes.index("no_correspondence")]["message"]
    assert "--skeletal-index" in msg and "--correspondence reverse" in msg


def test_curve_alone_with_reverse_is_scored_on_topology_and_centeredness():
    sh = shapes.cylinder(1500, seed=8)
    ev = evaluate(sh.cloud, curve=(sh.curve_vertices, sh.curve_edges), correspondence="reverse")
    assert ev.correspondence == "reverse" and ev.skeletal.source == "curve"
    assert len(ev.skeletal.points) == len(sh.cloud)
    # the projections of a cylinder's points onto its axis are its exact medial projections
    exact = evaluate(sh.cloud, sh.skeletal)
    assert np.allclose(ev.skeletal.points, sh.skeletal, atol=1e-9)
    assert ev.summary()["centeredness"]["skeletal"] == pytest.approx(exact.summary()["centeredness"]["skeletal"])
    assert ev.topology.bottleneck == pytest.approx(exact.topology.bottleneck)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(correspondence="nearest"), "correspondence must be one of"),
        (dict(skeletal_index=np.arange(5), correspondence="reverse"), "either"),
        (dict(skeletal_index=np.array([0.5, 1, 2, 3, 4])), "whole numbers"),
    ],
)
def test_bad_correspondence_arguments(kwargs, message):
    sh = shapes.cylinder(200, seed=1)
    with pytest.raises(SkelInputError, match=message):
        evaluate(sh.cloud, sh.skeletal[:5], **kwargs)
