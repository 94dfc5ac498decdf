"""Ground truth in compare: a shape's ``reference`` (a file or a ``{stem}`` template) reaches every job's
evaluation, results.csv's and the leaderboard's "ground truth" columns and report.html (numbers, and the
reference drawn under each skeleton); the job key follows the reference's bytes; a wrong reference
(missing, unreadable, empty, in another frame or units, cyclic where the shape is declared a tree) is
one line before any job runs."""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

from compare_helpers import make_dataset, manifest
from skelcore import shapes
from skelcore.cli import main
from skelcore.compare import Backend, run_compare
from skelcore.compare.jobs import make_jobs
from skelcore.compare.manifest import load_manifest
from skelcore.io import write_curve_ply, write_points_ply
from skelcore.scores import column_keys

GT = column_keys(group="ground truth", compared=True)
HELD = ("gt_held_precision", "gt_held_recall", "gt_held_f1")  # only with the reference's facts (none here)
SHIFT = 0.05

BODY = """
[[shapes]]
path = "clouds/*.ply"
reference = "refs/{stem}_ref.ply"
[[methods]]
name = "truth"
kind = "files"
curve = "skeletons/{stem}_curve.ply"
[[methods]]
name = "shifted"
kind = "files"
curve = "skeletons/{stem}_shifted.ply"
[[methods]]
name = "points"
kind = "files"
skeletal = "skeletons/{stem}_skeletal.ply"
[[conditions]]
name = "normal"
"""


@pytest.fixture(scope="module")
def root(tmp_path_factory):
    root = make_dataset(tmp_path_factory.mktemp("gt"))
    (root / "refs").mkdir()
    cyl, y = shapes.cylinder(700, seed=3), shapes.y_shape(700, seed=4)
    # the cylinder's reference carries its radius (0.5), the Y's has none (estimated from the cloud)
    write_curve_ply(root / "refs" / "cyl_ref.ply", cyl.curve_vertices, cyl.curve_edges,
                    scalars={"radius": np.full(len(cyl.curve_vertices), 0.5)})
    write_curve_ply(root / "refs" / "yshape_ref.ply", y.curve_vertices, y.curve_edges)
    # moved across every edge: the cylinder's axis is along z, the Y lies in the xy-plane
    for stem, sh, move in (("cyl", cyl, [SHIFT, 0, 0]), ("yshape", y, [0, 0, SHIFT])):
        write_curve_ply(root / "skeletons" / f"{stem}_shifted.ply", sh.curve_vertices + move, sh.curve_edges)
    return root


@pytest.fixture(scope="module")
def run(root):
    out = root / "out"
    result = run_compare(manifest(root, BODY), out, Backend("serial"), report=True)
    with open(out / "results.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    return out, rows, result


def test_the_manifest_resolves_each_shapes_reference(root):
    m = load_manifest(manifest(root, BODY))
    assert {s.name: s.reference for s in m.shapes} == {
        "cyl": str(root / "refs" / "cyl_ref.ply"), "yshape": str(root / "refs" / "yshape_ref.ply")}
    assert not any(s.tree for s in m.shapes)


def test_results_csv_carries_the_ground_truth_columns(run):
    _out, rows, _ = run
    by = {(r["shape"], r["method"]): r for r in rows}
    assert all(r["status"] == "ok" for r in rows)
    for shape in ("cyl", "yshape"):
        truth, shifted = by[(shape, "truth")], by[(shape, "shifted")]
        assert float(truth["gt_chamfer"]) == pytest.approx(0.0, abs=1e-12)
        assert float(truth["gt_f1"]) == 1.0 and float(truth["gt_length_ratio"]) == pytest.approx(1.0)
        assert float(truth["gt_endpoint_precision"]) == float(truth["gt_endpoint_recall"]) == 1.0
        assert float(shifted["gt_chamfer"]) == pytest.approx(SHIFT)  # every point SHIFT above the reference
        assert float(shifted["gt_f1"]) < 1.0
        assert all(by[(shape, "points")][k] == "" for k in GT)  # a skeletal set has no curve to compare
    # the cylinder's radius is its file's: SHIFT / 0.5 radii
    assert float(by[("cyl", "shifted")]["gt_chamfer_radii"]) == pytest.approx(SHIFT / 0.5)
    assert by[("yshape", "truth")]["gt_junction_precision"] == "1.0"
    assert by[("cyl", "truth")]["gt_junction_precision"] == ""  # no junction on either side: NaN
    assert all(r[k] == "" for r in rows for k in HELD)  # no facts: the held columns stay empty


def test_without_facts_the_records_have_no_held_scores(run):
    """A reference without facts (``reference_facts``) computes no held scores: absent from every
    job's record, not NaN-filled (docs/compare.md "Ground truth")."""
    out, rows, _ = run
    for path in (out / "jobs").glob("*.json"):
        rec = json.loads(path.read_text())
        assert rec["status"] == "ok" and not set(rec["scores"]) & set(HELD), path.name
        assert rec["evaluation"]["ground_truth"] is None or rec["evaluation"]["ground_truth"]["held_f1"] is None


def test_the_leaderboard_ranks_the_ground_truth_block(run):
    out, _rows, result = run
    board = result.leaderboard
    cols = board.columns()
    assert set(GT) - {"gt_junction_precision", "gt_junction_recall", *HELD} <= set(cols)
    assert not set(HELD) & set(cols)  # no facts: no held column on the board
    first_gt = cols.index("gt_chamfer_radii")
    assert cols[first_gt - 1] == "smoothness_curve"  # beside the paper's block
    rank = {e.method: e.rank for e in board.entries}
    assert rank["truth"]["gt_f1"] == 1 and rank["shifted"]["gt_f1"] == 2
    assert rank["truth"]["gt_chamfer"] == 1 and rank["points"]["gt_chamfer"] is None
    assert rank["truth"]["gt_length_ratio"] is None  # a fact, not ranked
    md = (out / "leaderboard.md").read_text()
    assert "gt_f1 ↑" in md and "gt_chamfer_radii ↓" in md and "held" not in md


def test_report_shows_the_numbers_and_draws_the_reference(run):
    out, rows, _ = run
    html = (out / "report.html").read_text()
    assert "ground truth:" in html and "thin grey line: the reference" in html
    from skelcore.compare.job_store import Store

    store = Store(out)
    key = next(r["key"] for r in rows if r["method"] == "truth" and r["shape"] == "yshape")
    arrays = store.arrays(key)
    assert arrays["reference_vertices"].shape == (31, 3) and len(arrays["reference_edges"]) == 30
    points = next(r["key"] for r in rows if r["method"] == "points")
    assert "reference_vertices" in store.arrays(points)  # drawn beside a skeletal set too


def test_the_job_key_follows_the_references_bytes(root, tmp_path):
    import shutil

    for sub in ("clouds", "skeletons", "refs"):
        shutil.copytree(root / sub, tmp_path / sub)
    keys = lambda body: {(j.shape.name, j.method.name): j.key for j in make_jobs(load_manifest(manifest(tmp_path, body)))}  # noqa: E731
    with_ref = keys(BODY)
    without = keys(BODY.replace('reference = "refs/{stem}_ref.ply"\n', ""))
    assert not set(with_ref.values()) & set(without.values())
    cyl = shapes.cylinder(700, seed=3)
    write_curve_ply(tmp_path / "refs" / "new.ply", cyl.curve_vertices * 1.01, cyl.curve_edges)
    (tmp_path / "refs" / "new.ply").replace(tmp_path / "refs" / "cyl_ref.ply")  # (skelcore never overwrites an input)
    edited = keys(BODY)
    assert [k for k in edited if edited[k] != with_ref[k]] == [k for k in with_ref if k[0] == "cyl"]
    assert keys(BODY.replace("reference", "tree = false\nreference")) == edited  # a declaration, not an input


def _write_bad(root, what: str) -> str:
    """A reference file for the cylinder that is wrong in one way; the manifest line naming it."""
    cyl = shapes.cylinder(700, seed=3)
    v, e = cyl.curve_vertices, cyl.curve_edges
    path = root / "refs" / f"bad_{what}.ply"
    if path.exists():
        pass
    elif what == "empty":
        write_points_ply(path, v)
    elif what == "millimetres":
        write_curve_ply(path, v * 1000, e)
    elif what == "elsewhere":
        write_curve_ply(path, v + [50, 0, 0], e)
    elif what == "cyclic":
        write_curve_ply(path, v, np.vstack([e, [[0, len(v) - 1]]]))
    elif what == "garbage":
        path.write_text("not a curve\n")
    elif what == "dots":  # vertices, no edge
        path = root / "refs" / "bad_dots.json"
        path.write_text(json.dumps({"vertices": v.tolist(), "edges": []}))
        return 'reference = "refs/bad_dots.json"'
    return f'reference = "refs/bad_{what}.ply"'


@pytest.mark.parametrize("what, extra, message", [
    ("missing", "", "reference refs/bad_missing.ply not found"),
    ("garbage", "", "reference refs/bad_garbage.ply: "),
    ("empty", "", "reference refs/bad_empty.ply: PLY file has no edges: it is a point set, not a curve skeleton"),
    ("dots", "", "reference refs/bad_dots.json: JSON file has no edges"),
    ("millimetres", "", "is not in the cloud's frame and units: only 5% of its vertices lie inside the cloud's "
                        "bounding box; its extent is 943 x the cloud's"),
    ("elsewhere", "", "is not in the cloud's frame and units: only 0% of its vertices"),
    ("cyclic", "tree = true\n", "reference refs/bad_cyclic.ply has 1 cycle(s) but the shape is declared a tree"),
    ("cyclic", "tree = 1\n", "tree must be true or false"),
])
def test_a_wrong_reference_is_one_line_and_nothing_runs(root, tmp_path, capsys, what, extra, message):
    line = _write_bad(root, what)
    body = BODY.replace('path = "clouds/*.ply"\nreference = "refs/{stem}_ref.ply"',
                        f'name = "cyl"\npath = "clouds/cyl.ply"\n{extra}{line}')
    m = manifest(root, body, name="bad.toml")
    out = tmp_path / "out"
    assert main(["compare", str(m), "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "bad.toml" in err and "shapes[0]" in err, err
    assert message in err, err
    assert not out.exists()


def test_a_tree_with_a_tree_reference_passes(root):
    body = BODY.replace('reference = "refs/{stem}_ref.ply"', 'reference = "refs/{stem}_ref.ply"\ntree = true')
    assert all(s.tree for s in load_manifest(manifest(root, body)).shapes)


def test_a_reference_without_a_template_names_one_file(root):
    body = BODY.replace('path = "clouds/*.ply"\nreference = "refs/{stem}_ref.ply"',
                        'path = "clouds/yshape.ply"\nreference = "refs/yshape_ref.ply"')
    (s,) = load_manifest(manifest(root, body)).shapes
    assert s.reference == str(root / "refs" / "yshape_ref.ply") and not math.isnan(len(s.reference))
