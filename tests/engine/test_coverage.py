

def test_coverage_is_skipped_above_coverage_max_points_and_says_so(tmp_path):
    """Exact skeletal coverage takes 15-45 s at 1M points on tubes (docs/metrics.md 5.2): above the
    limit the evaluation says why it is missing, in the JSON and on the command line, and still scores
    the rest."""
    import json
    import subprocess
    import sys

    from skelcore import Params, evaluate, shapes
    from skelcore.io import write_points_ply

    shape = shapes.cylinder(1500, 0.5, 4.0, seed=2)
    curve = (shape.curve_vertices, shape.curve_edges)
    full = evaluate(shape.cloud, shape.skeletal, curve)
    assert full.coverage_skeletal is not None and "coverage" not in full.not_computed
    cut = evaluate(shape.cloud, shape.skeletal, curve, Params(coverage_max_points=1000))
    assert cut.coverage_skeletal is None and cut.coverage_curve is None
    assert "1,500 points" in cut.not_computed["coverage"] and "coverage" not in cut.timings
    assert cut.summary()["boundedness"] == full.summary()["boundedness"]
    write_points_ply(tmp_path / "c.ply", shape.cloud)
    write_points_ply(tmp_path / "s.ply", shape.skeletal)
    run = subprocess.run(
        [sys.executable, "-m", "skelcore", "evaluate", str(tmp_path / "c.ply"), "--skeletal", str(tmp_path / "s.ply"),
         "--set", "coverage_max_points=1000", "--json", str(tmp_path / "o.json")],
        capture_output=True, text=True,
    )
    assert run.returncode == 0, run.stderr
    assert "not computed: coverage: the cloud has 1,500 points" in run.stderr
    assert "coverage_max_points" in json.loads((tmp_path / "o.json").read_text())["not_computed"]["coverage"]


def test_above_coverage_exact_points_coverage_is_estimated_on_a_subsample_and_says_so():
    """docs/metrics.md 5.2: above coverage_exact_points the gaps are found for a random subsample of the
    cloud and of the elements (radii from the whole cloud), every other point taking its nearest sampled
    point's answer.  On a torus with its skeletal set and with a third of it removed, the estimate keeps
    the verdicts: the fraction within 0.01, the same per-point verdict for >= 99 % of the points, the
    same missing part (share and depth) found by the diagnostics, and the JSON says how many were asked."""
    import numpy as np

    from skelcore import Params, evaluate, shapes
    from skelcore.diagnostics.missing_parts import missing_parts
    from skelcore.geometry import Normalization
    from skelcore.metrics.coverage import coverage

    shape = shapes.torus(40_000, R=1.0, r=0.3, seed=0)
    rng = np.random.default_rng(0)
    skel = shape.skeletal + rng.normal(scale=0.01, size=shape.skeletal.shape)
    ang = np.arctan2(skel[:, 1], skel[:, 0])
    cut = skel[~((ang > 0) & (ang < 2 * np.pi / 3))]
    p = Params()
    norm = Normalization.from_cloud(shape.cloud, p.normalize_by, p.normalized_size)
    cloud = norm.apply(shape.cloud)
    sampled = Params(coverage_exact_points=10_000)
    for elements in (skel, cut):
        exact = coverage(cloud, norm.apply(elements), p)
        est = coverage(cloud, norm.apply(elements), sampled)
        assert exact.subsample is None and "subsample" not in exact.to_dict()
        assert est.subsample == 10_000 and est.to_dict()["subsample"] == 10_000
        assert len(est.sample_rows) == 10_000 and len(est.covered) == len(cloud) == len(est.gap)
        assert abs(est.fraction - exact.fraction) <= 0.01
        assert np.mean(est.covered == exact.covered) >= 0.99
        assert est.fraction == est.covered.mean() and est.tau == exact.tau
        m_exact = missing_parts(cloud, norm.apply(elements), p, cov=exact)
        m_est = missing_parts(cloud, norm.apply(elements), sampled, cov=est)
        assert m_est.incomplete == m_exact.incomplete and m_est.subsample == 10_000
        assert m_est.completeness == est.fraction  # the two never disagree
        if m_exact.incomplete:
            a, b = m_exact.regions[0], m_est.regions[0]
            assert abs(a.share - b.share) <= 0.01 and abs(a.depth - b.depth) <= 0.15 * a.depth
    # in an evaluation: the JSON's coverage block says so
    ev = evaluate(shape.cloud[:12_000], shape.skeletal[:12_000], None, Params(coverage_exact_points=5_000))
    assert ev.coverage_dict()["skeletal"]["subsample"] == 5_000
