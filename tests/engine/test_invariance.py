"""Property tests: every metric is invariant under translation and uniform scaling of all inputs
together (the normalization of docs/metrics.md 0 removes them), and rays boundedness under rotation (docs/metrics.md 2)."""

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from skelcore import evaluate, shapes
from skelcore.metrics.boundedness import boundedness
from skelcore.geometry import Normalization

# 23 edges: 200 samples / 23 is far from a .5 rounding tie (16 equal edges would give 12.5 each,
# where rounding noise at another scale legitimately moves samples).
SHAPE = shapes.torus(900, R=1.0, r=0.35, n_curve=23, seed=21)
BASE = evaluate(SHAPE.cloud, SHAPE.skeletal, (SHAPE.curve_vertices, SHAPE.curve_edges))

coords = st.floats(-1e4, 1e4, allow_nan=False)
similar = settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@similar
@given(shift=st.tuples(coords, coords, coords), scale=st.floats(1e-3, 1e3))
def test_every_metric_is_invariant_under_translation_and_scaling(shift, scale):
    move = lambda x: np.asarray(x) * scale + np.array(shift)  # noqa: E731
    ev = evaluate(move(SHAPE.cloud), move(SHAPE.skeletal), (move(SHAPE.curve_vertices), SHAPE.curve_edges))
    np.testing.assert_allclose(ev.skeletal.boundedness, BASE.skeletal.boundedness, atol=1e-3)
    np.testing.assert_allclose(ev.skeletal.centeredness_raw, BASE.skeletal.centeredness_raw, atol=1e-6)
    np.testing.assert_allclose(ev.skeletal.smoothness, BASE.skeletal.smoothness, atol=1e-6)
    np.testing.assert_allclose(ev.curve.sample_boundedness, BASE.curve.sample_boundedness, atol=1e-3)
    np.testing.assert_allclose(ev.curve.sample_centeredness_raw, BASE.curve.sample_centeredness_raw, atol=1e-6)
    np.testing.assert_allclose(ev.curve.vertex_smoothness, BASE.curve.vertex_smoothness, atol=1e-9)
    assert ev.topology.bottleneck == pytest.approx(BASE.topology.bottleneck, rel=1e-6, abs=1e-12)
    assert ev.topology.wasserstein == pytest.approx(BASE.topology.wasserstein, rel=1e-6, abs=1e-12)
    assert ev.topology.n_bars == BASE.topology.n_bars


@similar
@given(quat=st.tuples(*[st.floats(-1, 1)] * 4).filter(lambda q: np.linalg.norm(q) > 0.1))
def test_rays_boundedness_is_rotation_invariant(quat):
    # normalized frame, rotation about the origin: only the estimator's own raster can differ
    norm = Normalization.from_cloud(SHAPE.cloud)
    cloud = norm.apply(SHAPE.cloud)
    queries = np.vstack([[0.0, 0.0, 0.0], norm.apply(SHAPE.curve_vertices[:6]), [[0.5, 0.5, 0.3]]])
    rot = Rotation.from_quat(np.array(quat) / np.linalg.norm(quat)).as_matrix()
    a = boundedness(cloud, queries)
    b = boundedness(cloud @ rot.T, queries @ rot.T)
    np.testing.assert_allclose(a, b, atol=0.02)  # each within 0.01 of the exact union area
