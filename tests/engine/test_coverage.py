

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
