"""Defects in compare: a job's defect warnings (skelcore.diagnostics.trust.DEFECT_CODES) reach results.csv by name,
fail the profiles that list them, keep the defective method out of the leaderboard's ranks (never shown
best), count in its "sound" column and are named beside its pictures in report.html."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

from compare_helpers import make_dataset, manifest
from skelcore import shapes
from skelcore.cli import main as main_cli
from skelcore.compare import Backend, run_compare
from skelcore.compare.profiles import load_profiles
from skelcore.io import write_curve_ply


def _collapsed(vertices: np.ndarray, factor: float = 0.02) -> np.ndarray:
    """The curve shrunk towards its centroid: it scores well on d_B, boundedness and centeredness."""
    c = vertices.mean(axis=0)
    return c + factor * (vertices - c)


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    root = make_dataset(tmp_path_factory.mktemp("defects"))
    for stem, shape in (("cyl", shapes.cylinder(700, seed=3)), ("yshape", shapes.y_shape(700, seed=4))):
        write_curve_ply(root / "skeletons" / f"{stem}_collapsed.ply", _collapsed(shape.curve_vertices),
                        shape.curve_edges)
    m = manifest(root, """
    [[shapes]]
    path = "clouds/*.ply"
    [[methods]]
    name = "truth"
    kind = "files"
    curve = "skeletons/{stem}_curve.ply"
    [[methods]]
    name = "collapsed"
    kind = "files"
    curve = "skeletons/{stem}_collapsed.ply"
    [[conditions]]
    name = "normal"
    """)
    out = root / "out"
    result = run_compare(m, out, Backend("serial"), report=True)
    with open(out / "results.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    return out, rows, result


def test_defects_are_named_in_results_csv_and_make_a_job_unsound(run):
    _out, rows, _ = run
    by = {(r["shape"], r["method"]): r for r in rows}
    for shape in ("cyl", "yshape"):
        bad, good = by[(shape, "collapsed")], by[(shape, "truth")]
        assert bad["status"] == good["status"] == "ok"
        assert "collapse" in bad["defects"].split(";") and bad["sound"] == "0"
        assert "collapse" in bad["warnings"].split(";")
        assert good["defects"] == "" and good["sound"] == "1"


def test_a_defective_job_fails_every_profile_that_applies(run):
    _out, rows, _ = run
    profiles = load_profiles()
    assert all("collapse" in p.fail_on for p in profiles)
    for r in rows:
        if r["method"] != "collapsed":
            continue
        for p in profiles:
            verdict = r[f"profile_{p.name}"]
            if p.when is None:
                assert verdict == "fail" and r[f"profile_{p.name}_reason"].startswith("defect: collapse")
            else:
                assert verdict == "n/a"


def test_the_defective_method_is_never_ranked_nor_shown_best(run):
    out, _rows, _ = run
    lines = (out / "leaderboard.md").read_text().splitlines()
    head = [c.strip() for c in lines[0].strip("|").split("|")]
    rows = {r[0]: r for r in ([c.strip() for c in line.strip("|").split("|")] for line in lines[2:4])}
    assert rows["truth"][head.index("sound")] == "2/2" and rows["collapsed"][head.index("sound")] == "0/2"
    scored = [i for i, h in enumerate(head) if h.split(" ")[0] in ("boundedness_curve", "centeredness_curve")]
    assert scored
    for i in scored:
        assert "†" in rows["collapsed"][i] and "(" not in rows["collapsed"][i]  # marked, no rank
        assert "†" not in rows["truth"][i] and rows["truth"][i].endswith("(1)")
    board = (out / "leaderboard.csv").read_text().splitlines()
    assert board[0].split(",")[4] == "n_sound"


def test_report_names_each_jobs_warnings_beside_its_pictures(run):
    out, _rows, _ = run
    page = (out / "report.html").read_text()
    assert "<ul class=warnings><li class=fail><b>collapse</b>" in page
    assert "fails on the defects" in page and "no warning" in page


def test_a_profile_file_with_an_unknown_defect_code_is_one_line(tmp_path, capsys):
    from skelcore.errors import SkelInputError

    bad = tmp_path / "p.toml"
    bad.write_text('[[profiles]]\nname = "x"\nfail_on = ["wobbly"]\n[[profiles.require]]\nmetric = "d_B"\nmax = 1\n')
    with pytest.raises(SkelInputError, match="fail_on must list defect codes"):
        load_profiles(bad)


def test_cli_prints_a_defects_block_and_strict_exits_3_on_a_defect(tmp_path, capsys):
    from skelcore.io import write_points_ply

    sh = shapes.cylinder(600, seed=1)
    cloud, good, bad = tmp_path / "c.ply", tmp_path / "good.ply", tmp_path / "bad.ply"
    write_points_ply(cloud, sh.cloud)
    write_curve_ply(good, sh.curve_vertices, sh.curve_edges)
    write_curve_ply(bad, _collapsed(sh.curve_vertices), sh.curve_edges)
    assert main_cli(["evaluate", str(cloud), "--curve", str(good), "--strict"]) == 0
    assert "defects: none found" in capsys.readouterr().out
    assert main_cli(["evaluate", str(cloud), "--curve", str(bad), "--strict"]) == 3
    text = capsys.readouterr().out
    assert "defects:\n  [collapse]" in text
