"""A compare run keeps each job's whole Evaluation (skeletons, raw local values, index, rows) and
``run_folder`` gives it back unchanged, read only, with one-line errors (the viewer's A/B
view opens the report's rows from the stored results)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from compare_helpers import make_dataset, manifest
from skelcore.errors import SkelInputError
from skelcore.compare import Backend, run_compare
from skelcore.compare.jobs import execute, make_jobs
from skelcore.compare.manifest import load_manifest
from skelcore.compare.finished_run import is_run_path, open_run
from skelcore.io import load_points, write_points_ply

BODY = """
[[shapes]]
path = "clouds/*.ply"
[[methods]]
name = "truth"
kind = "files"
curve = "skeletons/{stem}_curve.ply"
skeletal = "skeletons/{stem}_skeletal.ply"
[[methods]]
name = "sub"
kind = "files"
skeletal = "skeletons/{stem}_sub.ply"
skeletal_index = "skeletons/{stem}_sub.idx"
[[methods]]
name = "rev"
kind = "files"
skeletal = "skeletons/{stem}_curve.ply"
correspondence = "reverse"
[[methods]]
name = "builtin"
kind = "builtin"
[[conditions]]
name = "normal"
[[conditions]]
name = "noise"
noise = 0.05
"""


def add_index_method(root: Path) -> None:
    """skeletons/{stem}_sub.ply: every third true skeletal point; {stem}_sub.idx: their cloud rows."""
    for stem in ("cyl", "yshape"):
        sk = load_points(root / "skeletons" / f"{stem}_skeletal.ply")
        rows = np.arange(1, len(sk), 3)
        write_points_ply(root / "skeletons" / f"{stem}_sub.ply", sk[rows])
        (root / "skeletons" / f"{stem}_sub.idx").write_text("\n".join(map(str, rows)) + "\n")


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    root = make_dataset(tmp_path_factory.mktemp("stored"), n=600)
    add_index_method(root)
    m = manifest(root, BODY)
    res = run_compare(m, root / "out", Backend("serial"), report=False)
    assert res.summary.failed == 0
    return root, m, root / "out"


def _listing(folder: Path) -> dict[str, tuple[int, int]]:
    return {str(p.relative_to(folder)): (p.stat().st_size, p.stat().st_mtime_ns) for p in folder.rglob("*")}


def test_every_stored_evaluation_is_the_one_a_fresh_evaluation_gives(run_dir):
    """Independent check: each job executed again in this process gives the same local values and,
    at the run's thresholds and at others, the same scores as the rebuilt stored Evaluation."""
    _root, m, out = run_dir
    run = open_run(out)
    fresh_jobs = {j.key: j for j in make_jobs(load_manifest(m))}
    assert len(run.jobs) == 10  # 2 shapes x (3 files methods x normal + builtin x 2 conditions)
    for entry in run.jobs:
        stored = run.evaluation(entry)
        fresh = execute(fresh_jobs[entry.key]).evaluation
        np.testing.assert_array_equal(stored.cloud, fresh.cloud)
        assert stored.correspondence == fresh.correspondence
        for b_star, c_star in ((None, None), (0.5, 0.3), (0.95, 0.9)):
            a, b = stored.summary(b_star, c_star), fresh.summary(b_star, c_star)
            for group in ("boundedness", "centeredness", "smoothness", "counts", "topology"):
                assert a[group] == b[group], (entry.label, group, b_star)
            assert a["coverage"] == b["coverage"]
        if fresh.skeletal is not None:
            np.testing.assert_array_equal(stored.skeletal.points, fresh.skeletal.points)
            np.testing.assert_array_equal(stored.skeletal.centeredness_raw, fresh.skeletal.centeredness_raw)
            np.testing.assert_array_equal(stored.skeletal.boundedness, fresh.skeletal.boundedness)
        if fresh.curve is not None:
            np.testing.assert_array_equal(stored.curve.curve.edges, fresh.curve.curve.edges)
            np.testing.assert_array_equal(stored.curve.sample_centeredness_raw, fresh.curve.sample_centeredness_raw)
            np.testing.assert_array_equal(stored.curve.sample_edge, fresh.curve.sample_edge)
        assert [w.code for w in stored.warnings] == [w.code for w in fresh.warnings]
        assert stored.params == fresh.params


def test_the_skeletal_index_and_reverse_rows_are_kept(run_dir):
    root, _m, out = run_dir
    run = open_run(out)
    ev = run.evaluation(run.find("cyl", "sub"))
    assert ev.correspondence == "index"
    idx = np.loadtxt(root / "skeletons" / "cyl_sub.idx", dtype=np.int64)
    np.testing.assert_array_equal(ev.skeletal.index, idx)
    rev = run.evaluation(run.find("yshape", "rev"))
    assert rev.correspondence == "reverse" and len(rev.skeletal.rows) == len(rev.cloud)
    noisy = run.evaluation(run.find("cyl", "builtin", "noise"))
    clean = run.evaluation(run.find("cyl", "builtin", "normal"))
    assert noisy.cloud.shape == clean.cloud.shape and not np.array_equal(noisy.cloud, clean.cloud)


def test_reading_a_run_writes_nothing(run_dir):
    _root, _m, out = run_dir
    before = _listing(out)
    run = open_run(out / "index.json")
    for entry in run.jobs:
        run.evaluation(entry)
        run.status(entry)
    assert _listing(out) == before
    assert is_run_path(out) and is_run_path(out / "index.json") and not is_run_path(out / "jobs")


def test_lookups_name_the_choices(run_dir):
    _root, _m, out = run_dir
    run = open_run(out)
    assert run.shapes == ["cyl", "yshape"] and run.methods == ["truth", "sub", "rev", "builtin"]
    assert run.methods_for("cyl", "noise") == ["builtin"]
    assert run.find(None, "truth").condition == "normal"  # defaults: first dataset, first condition
    cases = [(("sphere", "truth"), "unknown dataset 'sphere': the run has 'cyl', 'yshape'"),
             (("cyl", "nope"), "unknown method 'nope': the run has 'truth', 'sub', 'rev', 'builtin'"),
             (("cyl", "truth", "blur"), "unknown condition 'blur'"),
             (("cyl", "truth", "noise"), "method 'truth' has no job for cyl under condition 'noise'"),
             (("cyl", "truth", "normal", 7), "unknown seed 7 for cyl / normal: the run has 0")]
    for args, message in cases:
        with pytest.raises(SkelInputError, match=message) as info:
            run.find(*args)
        assert "\n" not in str(info.value) and str(out) in str(info.value)


def test_bad_folders_and_bad_jobs_are_one_line_errors(run_dir, tmp_path):
    _root, _m, out = run_dir
    with pytest.raises(SkelInputError, match="no such folder"):
        open_run(tmp_path / "missing")
    (tmp_path / "empty").mkdir()
    with pytest.raises(SkelInputError, match="no index.json"):
        open_run(tmp_path / "empty")
    copy = tmp_path / "copy"
    shutil.copytree(out, copy)
    run = open_run(copy)
    failed, old, unfinished = run.find("cyl", "truth"), run.find("cyl", "rev"), run.find("yshape", "truth")
    rec_path = copy / "jobs" / f"{failed.key}.json"
    rec = json.loads(rec_path.read_text())
    rec.update(status="failed", error="the skeleton command exited with status 139")
    rec_path.write_text(json.dumps(rec))
    with pytest.raises(SkelInputError, match="cyl / truth / normal / seed 0 failed: the skeleton command exited"):
        run.evaluation(failed)
    # a store written before the evaluations were kept: the report's arrays only
    npz = copy / "jobs" / f"{old.key}.npz"
    with np.load(npz) as z:
        arrays = {k: z[k] for k in z.files if not k.startswith("ev_")}
    with open(npz, "wb") as fh:
        np.savez_compressed(fh, **arrays)
    with pytest.raises(SkelInputError, match="this run stored no skeletons"):
        run.evaluation(old)
    (copy / "jobs" / f"{unfinished.key}.json").unlink()
    assert run.status(unfinished)[0] == "missing"
    with pytest.raises(SkelInputError, match="has not finished"):
        run.evaluation(unfinished)
