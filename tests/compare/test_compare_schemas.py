"""Compare's job records (jobs/KEY.json) and results.csv rows follow their JSON Schemas
(skelcore/io/schemas, docs/output_formats.md): a small run with a finished and a failing method, the
rows of jobs not run yet, and records or rows missing a required key or holding a wrong value."""

from __future__ import annotations

import copy
import csv
import io
import json

import pytest

from compare_helpers import command, make_dataset, manifest
from skelcore.compare import Backend, run_compare
from skelcore.compare.job_store import Store
from skelcore.compare.jobs import make_jobs
from skelcore.compare.manifest import load_manifest
from skelcore.compare.profiles import load_profiles
from skelcore.compare.results_csv import collect_rows, results_csv_text
from skelcore.io.schemas import SCHEMA_VERSION, validator

pytest.importorskip("jsonschema")


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    root = make_dataset(tmp_path_factory.mktemp("schemas"), n=500)
    m = manifest(root, f"""
    [evaluation]
    curve_samples = 60
    [[shapes]]
    path = "clouds/*.ply"
    [[methods]]
    name = "truth"
    kind = "files"
    curve = "skeletons/{{stem}}_curve.ply"
    skeletal = "skeletons/{{stem}}_skeletal.ply"
    [[methods]]
    name = "crash"
    kind = "command"
    command = "{command('crash')}"
    [[conditions]]
    name = "normal"
    """)
    res = run_compare(m, root / "out", Backend("serial"), report=False)
    assert res.summary.ok == 2 and res.summary.failed == 2
    return root, m


def _errors(name: str, doc, part: str | None = None) -> list[str]:
    return [f"{'/'.join(map(str, e.absolute_path))}: {e.message}" for e in validator(name, part).iter_errors(doc)]


def _records(root) -> list[dict]:
    return [json.loads(p.read_text()) for p in sorted((root / "out" / "jobs").glob("*.json"))]


def _read(text: str) -> tuple[list[str], list[dict[str, str]]]:
    reader = csv.DictReader(io.StringIO(text))
    return list(reader.fieldnames or []), list(reader)


def test_job_records_validate(run):
    root, _m = run
    records = _records(root)
    assert sorted(r["status"] for r in records) == ["failed", "failed", "ok", "ok"]
    for rec in records:
        assert rec["schema_version"] == SCHEMA_VERSION and next(iter(rec)) == "schema_version"
        assert _errors("compare_job", rec) == [], rec["method"]


def test_results_csv_header_and_rows_validate(run):
    root, _m = run
    header, rows = _read((root / "out" / "results.csv").read_text())
    assert header[-1] == "schema_version" and any(h.startswith("profile_") for h in header)
    assert _errors("results_csv", header, "header") == []
    assert len(rows) == 4 and {r["status"] for r in rows} == {"ok", "failed"}
    for row in rows:
        assert row["schema_version"] == SCHEMA_VERSION
        assert _errors("results_csv", row) == [], row["method"]


def test_rows_of_jobs_not_run_yet_validate(run, tmp_path):
    """A run stopped early: its jobs without a record are rows with status "missing"."""
    _root, m = run
    jobs = make_jobs(load_manifest(m))
    profiles = load_profiles()
    header, rows = _read(results_csv_text(collect_rows(jobs, Store(tmp_path / "empty"), profiles), profiles))
    assert {r["status"] for r in rows} == {"missing"}
    assert _errors("results_csv", header, "header") == []
    assert all(_errors("results_csv", r) == [] for r in rows)


def test_the_record_of_a_job_whose_worker_died_validates(run, tmp_path):
    from skelcore.compare.backends import _failed

    _root, m = run
    store = Store(tmp_path / "out")
    job = make_jobs(load_manifest(m))[0]
    store.put(_failed(job, "the worker process died"))
    assert _errors("compare_job", store.get(job.key)) == []


def test_a_record_missing_a_required_key_or_with_a_wrong_value_fails(run):
    root, _m = run
    ok = next(r for r in _records(root) if r["status"] == "ok")
    for key in ("schema_version", "key", "status", "scores"):
        rec = copy.deepcopy(ok)
        del rec[key]
        assert f": '{key}' is a required property" in _errors("compare_job", rec)
    rec = copy.deepcopy(ok)
    del rec["evaluation"]  # an ok job has its evaluation document
    assert _errors("compare_job", rec) == [": 'evaluation' is a required property"]
    rec = copy.deepcopy(ok)
    del rec["evaluation"]["counts"]  # ... checked against the evaluation schema
    del rec["scores"]["d_B"]
    assert sorted(_errors("compare_job", rec)) == ["evaluation: 'counts' is a required property",
                                                   "scores: 'd_B' is a required property"]
    rec = copy.deepcopy(ok)
    rec["status"], rec["seed"] = "done", "0"
    assert len(_errors("compare_job", rec)) == 2


def test_a_row_missing_a_column_or_with_a_wrong_cell_fails(run):
    root, _m = run
    header, rows = _read((root / "out" / "results.csv").read_text())
    ok = next(r for r in rows if r["status"] == "ok")
    for col in ("key", "d_B", "schema_version"):
        row = dict(ok)
        del row[col]
        assert _errors("results_csv", row) == [f": '{col}' is a required property"]
    row = dict(ok, d_B="nan", seed="", sound="yes", profile_grasping="maybe", profile_grasping_score="x")
    assert len(_errors("results_csv", row)) == 5
    assert _errors("results_csv", dict(ok, a_later_column="1")) == []  # added columns are not errors
    assert _errors("results_csv", header[1:], "header") != []  # the fixed columns come first, in order
