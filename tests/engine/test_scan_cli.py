"""The real-scan options end to end: ``--viewpoint`` (and a PCD's VIEWPOINT), ``--remove-outliers``,
``--cap-openings`` on the command line; the ``scan`` block of the JSON and its round trip; per-shape
viewpoints in compare manifests."""

from __future__ import annotations

import json

import numpy as np
import pytest

from compare_helpers import make_dataset, manifest
from skelcore import evaluate, shapes
from skelcore.cli import main
from skelcore.compare.jobs import execute, make_jobs
from skelcore.compare.manifest import load_manifest
from skelcore.errors import SkelInputError
from skelcore.io import pcd_viewpoint, write_curve_ply, write_points_ply
from skelcore.io.evaluation_files import load_evaluation, save_evaluation
from skelcore.io.json_numbers import json_safe


@pytest.fixture(scope="module")
def front(tmp_path_factory):
    """The front half (y > 0) of a cylinder as PLY files and as PCDs with and without a VIEWPOINT."""
    d = tmp_path_factory.mktemp("front")
    c = shapes.cylinder(3000)
    k = c.cloud[:, 1] > 0
    write_points_ply(d / "cloud.ply", c.cloud[k])
    write_points_ply(d / "skel.ply", c.skeletal[k])
    write_curve_ply(d / "curve.ply", c.curve_vertices, c.curve_edges)
    rows = "\n".join(" ".join(f"{x:.6f}" for x in p) for p in c.cloud[k])
    for name, vp in (("seen.pcd", "0 40 2 1 0 0 0"), ("default.pcd", "0 0 0 1 0 0 0"), ("bad.pcd", "0 40 2")):
        (d / name).write_text(f"VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {k.sum()}\n"
                              f"HEIGHT 1\nVIEWPOINT {vp}\nPOINTS {k.sum()}\nDATA ascii\n{rows}\n")
    return d


def run(*argv):
    return main([str(a) for a in argv])


def test_viewpoint_flags_score_what_was_seen(front, tmp_path, capsys):
    out = tmp_path / "r.json"
    assert run("evaluate", front / "cloud.ply", "--curve", front / "curve.ply", "--quiet", "--json", out) == 0
    assert "open_surface" in capsys.readouterr().err
    paper = json.loads(out.read_text())
    assert paper["boundedness"]["curve"] < 0.05 and paper["scan"]["escaping"]["curve"] > 0.9
    assert run("evaluate", front / "cloud.ply", "--curve", front / "curve.ply", "--quiet", "--json", out,
               "--viewpoint", 0, 40, 2, "--viewpoint", 5, 40, 2) == 0
    doc = json.loads(out.read_text())
    assert doc["scan"]["viewpoints"] == [[0.0, 40.0, 2.0], [5.0, 40.0, 2.0]]
    assert doc["boundedness"]["curve"] >= 0.95 and doc["warnings"] == []


@pytest.mark.parametrize("argv, words", [
    (["--viewpoint", "0", "nan", "2"], "finite"),
    (["--viewpoint", "0", "40"], "expected 3 arguments"),
    (["--viewpoint", "0", "40", "2", "--boundedness-method", "paper"], "rays"),
])
def test_bad_viewpoints_exit_2_with_one_line(front, capsys, argv, words):
    with pytest.raises(SystemExit) if "expected" in words else _noop():
        code = run("evaluate", front / "cloud.ply", "--curve", front / "curve.ply", "--quiet", *argv)
        assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert words in err[-1]


class _noop:
    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


def test_a_pcd_viewpoint_is_used_unless_it_is_the_default(front, tmp_path, capsys):
    assert pcd_viewpoint(front / "seen.pcd").tolist() == [0.0, 40.0, 2.0]
    assert pcd_viewpoint(front / "default.pcd") is None and pcd_viewpoint(front / "cloud.ply") is None
    out = tmp_path / "r.json"
    assert run("evaluate", front / "seen.pcd", "--curve", front / "curve.ply", "--quiet", "--json", out) == 0
    assert "from the PCD header" in capsys.readouterr().err
    assert json.loads(out.read_text())["scan"]["viewpoints"] == [[0.0, 40.0, 2.0]]
    assert run("evaluate", front / "default.pcd", "--curve", front / "curve.ply", "--quiet", "--json", out) == 0
    assert json.loads(out.read_text())["scan"]["viewpoints"] == []  # open_surface's report, no viewpoint
    assert run("evaluate", front / "bad.pcd", "--curve", front / "curve.ply", "--quiet") == 2
    assert "VIEWPOINT must be 7" in capsys.readouterr().err


def test_cap_openings_says_why_it_did_not_cap(front, capsys):
    assert run("evaluate", front / "cloud.ply", "--curve", front / "curve.ply", "--quiet", "--cap-openings") == 0
    lines = [s for s in capsys.readouterr().err.splitlines() if "--cap-openings" in s and "not capped" in s]
    assert len(lines) == 1 and "too large" in lines[0]


def test_remove_outliers_prints_what_it_left_out(tmp_path, capsys):
    t = shapes.torus(1500)
    extra = np.array([[40.0, 0, 0]])
    write_points_ply(tmp_path / "c.ply", np.vstack([t.cloud, extra]))
    write_points_ply(tmp_path / "s.ply", np.vstack([t.skeletal, extra]))
    assert run("evaluate", tmp_path / "c.ply", "--skeletal", tmp_path / "s.ply", "--quiet") == 0
    assert "[outliers]" in capsys.readouterr().err
    assert run("evaluate", tmp_path / "c.ply", "--skeletal", tmp_path / "s.ply", "--quiet", "--remove-outliers") == 0
    err = capsys.readouterr().err
    assert "1 cloud point(s) and 1 skeletal row(s) left out" in err and "[outliers]" not in err


def test_the_scan_report_round_trips_through_the_stored_files(tmp_path):
    t = shapes.cylinder(2000, capped=False)
    ev = evaluate(t.cloud, t.skeletal, (t.curve_vertices, t.curve_edges), viewpoints=[0.0, 30.0, 2.0],
                  cap_openings=True)
    save_evaluation(ev, tmp_path / "e.npz", tmp_path / "e.json")
    back = load_evaluation(tmp_path / "e.npz", tmp_path / "e.json")
    assert back.scan.to_dict() == json_safe(ev.scan.to_dict())  # NaN (no local radius) written null
    assert [len(r) for r in back.scan.opening_rows()] == [len(o["rows"]) for o in ev.scan.openings]


def test_manifest_viewpoints_per_shape(tmp_path):
    root = make_dataset(tmp_path, n=300)
    body = """
    [[shapes]]
    path = "clouds/cyl.ply"
    viewpoint = [0.0, 30.0, 2.0]
    [[shapes]]
    path = "clouds/yshape.ply"
    viewpoint = [[0.0, 30.0, 0.0], [30.0, 0.0, 0.0]]
    [[methods]]
    name = "truth"
    kind = "files"
    curve = "skeletons/{stem}_curve.ply"
    """
    m = load_manifest(manifest(root, body))
    assert [s.viewpoints for s in m.shapes] == [((0.0, 30.0, 2.0),), ((0.0, 30.0, 0.0), (30.0, 0.0, 0.0))]
    jobs = make_jobs(m)
    plain = make_jobs(load_manifest(manifest(root, body.replace("viewpoint", "# viewpoint"), "plain.toml")))
    assert jobs[0].key != plain[0].key  # a viewpoint changes the result, so the key
    out = execute(jobs[0])
    assert out.evaluation.scan.viewpoints == [[0.0, 30.0, 2.0]]
    bad = body.replace("viewpoint = [0.0, 30.0, 2.0]", "viewpoint = [0.0, 30.0]")
    with pytest.raises(SkelInputError, match="viewpoint must be"):
        load_manifest(manifest(root, bad, "bad.toml"))
