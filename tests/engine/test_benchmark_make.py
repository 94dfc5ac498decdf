"""``skelcore bench make DIR``: the small suite's files, determinism (same seed, same bytes), resume,
the refusal of a folder that is not a benchmark, the compare manifest (skelcore.benchmark.generate)."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

import skelcore
from skelcore.benchmark import make_benchmark, read_reference, suite_cases
from skelcore.cli.main import main
from skelcore.errors import SkelInputError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


def _files(folder: Path) -> dict[str, bytes]:
    """Every file's bytes; the run marker's without its creation time."""
    out = {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}
    marker = json.loads(out.pop(".skelscope-run"))
    out[".skelscope-run"] = json.dumps({k: v for k, v in marker.items() if k != "created"}).encode()
    return out


@pytest.fixture(scope="module")
def small(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("bench") / "small"
    make_benchmark(folder, "small", 0)
    return folder


def test_small_suite_writes_every_case(small):
    cases = suite_cases("small")
    doc = json.loads((small / "suite.json").read_text())
    assert [c["name"] for c in doc["cases"]] == [c.name for c in cases]
    assert (doc["suite"], doc["seed"]) == ("small", 0)
    for rec in doc["cases"]:
        assert (small / rec["files"]["cloud"]).is_file() and (small / rec["files"]["reference"]).is_file()
        assert rec == json.loads((small / "cases" / f"{rec['name']}.json").read_text())
    assert {c["curve_skeleton"] for c in doc["cases"] if c["shape"] == "plate"} == {
        "curve skeleton ill-posed: the plate's medial axis is a sheet; the reference is only the rim's centre circle"}
    marker = json.loads((small / ".skelscope-run").read_text())  # compare's run marker, kind "bench"
    assert (marker["kind"], marker["suite"], marker["seed"]) == ("bench", "small", 0)


@pytest.mark.parametrize("case, count", [
    ("junction_y__clean", 1200), ("torus__outliers-0.05", 1260), ("junction_y__crop-0.25", 900),
    ("tube_a__nonuniform-10x", 1200),
])
def test_point_counts(small, case, count):
    cloud = skelcore.load_cloud(small / "clouds" / f"{case}.ply")
    assert len(cloud) == count
    rec = json.loads((small / "cases" / f"{case}.json").read_text())
    assert rec["points"] == count


def test_partial_scans_have_fewer_points(small):
    views = skelcore.load_cloud(small / "clouds" / "junction_y__views-1.ply")
    holes = skelcore.load_cloud(small / "clouds" / "torus__holes-3x0.5.ply")
    assert 400 < len(views) < 800 and 1100 < len(holes) < 1200


def test_reference_files_carry_the_radius(small):
    ref = read_reference(small / "truth" / "junction_y__clean_reference.ply")
    assert ref.radius is not None and len(ref.radius) == ref.curve.n_vertices
    assert ref.radius.max() == pytest.approx(0.30, abs=1e-6)  # float32 in the file
    deg = ref.curve.degrees()
    assert (np.sum(deg >= 3), np.sum(deg == 1)) == (1, 3)
    crop = read_reference(small / "truth" / "junction_y__crop-0.25_reference.ply")
    assert crop.curve.edge_lengths().sum() < ref.curve.edge_lengths().sum()


def test_reader_without_radius_and_with_a_bad_radius(tmp_path):
    from skelcore.io import write_curve_ply

    v = np.array([[0.0, 0, 0], [1, 0, 0]])
    write_curve_ply(tmp_path / "plain.ply", v, [[0, 1]])
    assert read_reference(tmp_path / "plain.ply").radius is None
    write_curve_ply(tmp_path / "bad.ply", v, [[0, 1]], scalars={"radius": np.array([0.1, -1.0])})
    with pytest.raises(SkelInputError, match="bad.ply: reference radius must be finite and > 0"):
        read_reference(tmp_path / "bad.ply")


def test_clean_references_lie_inside_their_clouds(small):
    for case in ("junction_y__clean", "torus__clean", "tube_a__clean", "plate__clean"):
        ref = read_reference(small / "truth" / f"{case}_reference.ply")
        ev = skelcore.evaluate(skelcore.load_cloud(small / "clouds" / f"{case}.ply"), curve=ref.curve)
        assert ev.summary()["boundedness"]["curve"] >= 0.98, case


def test_same_seed_same_bytes_other_seed_other_clouds(small, tmp_path):
    make_benchmark(tmp_path / "again", "small", 0)
    assert _files(tmp_path / "again") == _files(small)
    make_benchmark(tmp_path / "other", "small", 1)
    a = (small / "clouds" / "tube_a__clean.ply").read_bytes()
    assert (tmp_path / "other" / "clouds" / "tube_a__clean.ply").read_bytes() != a


def test_rerun_skips_finished_cases_and_remakes_missing_ones(small, tmp_path):
    import shutil

    folder = tmp_path / "copy"
    shutil.copytree(small, folder)
    before = _files(folder)
    again = make_benchmark(folder, "small", 0)
    assert (again.made, again.kept) == (0, 10)
    (folder / "clouds" / "torus__clean.ply").unlink()
    (folder / "cases" / "tube_a__clean.json").write_text("{not json")
    again = make_benchmark(folder, "small", 0)
    assert (again.made, again.kept) == (2, 8)
    assert _files(folder) == before


def test_a_folder_that_is_not_a_benchmark_is_refused(tmp_path, capsys):
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("keep me")
    assert main(["bench", "make", str(mine), "--suite", "small", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("skelcore: error: ") and "is not a skelcore bench run" in err
    assert sorted(p.name for p in mine.iterdir()) == ["notes.txt"]
    (tmp_path / "file").write_text("x")
    assert main(["bench", "make", str(tmp_path / "file"), "--quiet"]) == 2
    assert "is a file" in capsys.readouterr().err
    assert main(["bench", "make", str(mine), "--suite", "small", "--quiet", "--force"]) == 0
    assert (mine / "notes.txt").read_text() == "keep me" and (mine / "suite.json").is_file()


def test_another_suite_or_seed_needs_force(small, tmp_path, capsys):
    import shutil

    folder = tmp_path / "copy"
    shutil.copytree(small, folder)
    assert main(["bench", "make", str(folder), "--suite", "small", "--seed", "4", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "holds a bench run of suite 'small', seed 0, generator" in err and err.count("\n") == 1
    assert "not of suite 'small', seed 4" in err and "--force" in err
    (folder / "clouds" / "stale_case.ply").write_text("not ours")
    for sub, name in (("cases", "ghost.json"), ("clouds", "ghost.ply"), ("truth", "ghost_reference.ply")):
        (folder / sub / name).write_text("{}")  # a case of ours that the new suite does not have
    assert main(["bench", "make", str(folder), "--suite", "small", "--seed", "4", "--quiet", "--force"]) == 0
    assert "10 cases of the 'small' suite (seed 4)" in capsys.readouterr().out
    assert json.loads((folder / "suite.json").read_text())["seed"] == 4
    assert (folder / "clouds" / "stale_case.ply").read_text() == "not ours"  # not one of our records
    assert not any((folder / sub / name).exists() for sub, name in (
        ("cases", "ghost.json"), ("clouds", "ghost.ply"), ("truth", "ghost_reference.ply")))


def test_compare_manifest_names_every_case_with_its_reference(small):
    from skelcore.compare.manifest import parse_manifest

    doc = tomllib.loads((small / "compare.toml").read_text())
    assert [m["method"] for m in doc["methods"]] == ["cao", "skelscope"]
    assert all(m["kind"] == "builtin" for m in doc["methods"])
    names = [s["name"] for s in doc["shapes"]]
    assert names == [c.name for c in suite_cases("small")]
    for s in doc["shapes"]:
        assert (small / s["reference"].replace("{stem}", s["name"])).is_file()
        assert Path(s["path"]).stem == s["name"]  # {stem} is the same whether it means name or file stem
    without = {**doc, "shapes": [{k: v for k, v in s.items() if k != "reference"} for s in doc["shapes"]]}
    m = parse_manifest(without, str(small / "compare.toml"))  # otherwise a valid compare manifest
    assert [s.name for s in m.shapes] == names
    # a one-sided scan carries the sensors it was made from (compare scores what they saw)
    views = {s.name: s.viewpoints for s in m.shapes}
    rec = json.loads((small / "cases" / "junction_y__views-1.json").read_text())
    assert views["junction_y__views-1"] == tuple(tuple(e) for e in rec["scan"]["viewpoints"]) and len(rec["scan"]["viewpoints"]) == 1
    assert all(v == () for name, v in views.items() if "views" not in name)


def test_the_folder_marker_is_compares_run_marker(tmp_path, capsys):
    """bench make claims its folder with compare's run marker (kind "bench"): a compare run, a
    benchmark made before that marker and a benchmark's folder given to compare are refused with one
    line, nothing touched."""
    from skelcore.compare.run_marker import claim_run_folder

    legacy = tmp_path / "legacy"
    legacy.mkdir()
    (legacy / ".skelscope-bench").write_text('{"skelscope_bench": 1, "suite": "small", "seed": 0}')
    (legacy / "suite.json").write_text("{}")
    assert main(["bench", "make", str(legacy), "--suite", "small", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "made before skelcore marked its runs" in err and "--force once" in err
    assert sorted(p.name for p in legacy.iterdir()) == [".skelscope-bench", "suite.json"]
    run = tmp_path / "run"
    claim_run_folder(run, "compare")
    (run / "results.csv").write_text("mine")
    assert main(["bench", "make", str(run), "--suite", "small", "--quiet"]) == 2
    assert "is a skelcore 'compare' run, not a bench run" in capsys.readouterr().err
    assert (run / "results.csv").read_text() == "mine" and not (run / "clouds").exists()
    bench = tmp_path / "bench"
    assert main(["bench", "make", str(bench), "--suite", "small", "--quiet"]) == 0
    capsys.readouterr()
    with pytest.raises(SkelInputError, match="is a skelcore 'bench' run, not a compare run"):
        claim_run_folder(bench, "compare")


def test_bench_make_then_the_compare_command_it_prints(tmp_path, capsys):
    """End to end: the small suite, then the printed ``skelcore compare`` command with the
    built-in cao alone (the suite's manifest less its skelscope method, to keep the test short):
    every job finishes and results.csv has the ground-truth columns filled, the references' radius
    read from their files; a rerun does nothing again."""
    import csv
    import re
    import shlex

    from skelcore.scores import column_keys

    bench = tmp_path / "bench"
    assert main(["bench", "make", str(bench), "--suite", "small", "--quiet"]) == 0
    printed = re.search(r"^run them: (skelcore compare .*)$", capsys.readouterr().out, re.M).group(1)
    argv = shlex.split(printed)[1:]
    assert argv[:2] == ["compare", str(bench / "compare.toml")] and argv[2:] == ["--out", "RUN_DIR"]
    doc = (bench / "compare.toml").read_text()
    cao = doc.replace('[[methods]]\nname = "skelscope"\nkind = "builtin"\nmethod = "skelscope"\n\n', "")
    assert cao != doc
    (bench / "compare_cao.toml").write_text(cao)
    run = tmp_path / "run"
    argv = ["compare", str(bench / "compare_cao.toml"), "--out", str(run), "--jobs", "1", "--no-report", "--quiet"]
    assert main(argv) == 0
    with open(run / "results.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["shape"] for r in rows] == [c.name for c in suite_cases("small")]
    # every column but the node scores, NaN where there is no such node (a torus has no endpoint)
    # and the held scores empty: a generated suite's references lie on their shapes, no facts file
    held = [k for k in column_keys(group="ground truth", compared=True) if k.startswith("gt_held_")]
    always = [k for k in column_keys(group="ground truth", compared=True)
              if "junction" not in k and "endpoint" not in k and k not in held]
    assert held and "reference_facts" not in doc
    for r in rows:
        assert r["status"] == "ok" and r["method"] == "cao", r["error"]
        assert all(r[k] != "" for k in always) and all(r[k] == "" for k in held), r["shape"]
        assert 0 <= float(r["gt_f1"]) <= 1 and float(r["gt_chamfer_radii"]) >= 0
    by = {r["shape"]: r for r in rows}
    assert by["junction_y__clean"]["gt_junction_recall"] != "" and by["tube_a__clean"]["gt_junction_recall"] == ""
    assert by["tube_a__clean"]["gt_endpoint_recall"] != "" and by["torus__clean"]["gt_endpoint_recall"] == ""
    assert float(by["tube_a__clean"]["gt_f1"]) > 0.5  # cao on a clean tube: most of it within a radius
    record = json.loads(next((run / "jobs").glob("*.json")).read_text())
    assert record["evaluation"]["ground_truth"]["radius_source"] == "reference"
    capsys.readouterr()
    assert main(argv) == 0
    assert "10 jobs: 10 already done" in capsys.readouterr().out
