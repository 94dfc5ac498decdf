"""Commands in manifests: ``{python}`` is the interpreter running skelcore, so the shipped
samples manifest's external method runs whatever ``python3`` is on PATH; and ``files`` methods map
their skeletons with ``scale`` / ``offset`` as ``evaluate --skeleton-scale/--skeleton-offset``
does."""

from __future__ import annotations

import dataclasses
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from compare_helpers import make_dataset, manifest
from skelcore import io, shapes
from skelcore.cli import main
from skelcore.compare import Backend, load_manifest, run_compare
from skelcore.compare.jobs import SCORE_COLUMNS, make_jobs, run_job
from skelcore.compare.manifest import command_argv
from skelcore.errors import SkelInputError

ROOT = Path(__file__).resolve().parents[2]
SAMPLES = ROOT / "resources" / "compare" / "samples.toml"


# ---- {python} ------------------------------------------------------------------------------------

def test_python_placeholder_is_this_interpreter_in_every_word_and_never_expanded_twice():
    argv = command_argv("{python} -X utf8 tool.py --interp={python} {in} {out_curve}", "cmd",
                        {"{in}": "/data/{python}/c.ply", "{out_curve}": "/o/c.ply"})
    assert argv == [sys.executable, "-X", "utf8", "tool.py", f"--interp={sys.executable}",
                    "/data/{python}/c.ply", "/o/c.ply"]
    with pytest.raises(SkelInputError, match="needs an {in} placeholder"):
        command_argv("{python} tool.py {out_curve}", "cmd")


def _foreign_python3(tmp_path: Path) -> Path:
    """A bin folder whose ``python3`` is a real interpreter of this machine that cannot import
    skelcore (the system Python outside our venv), as for a user without an activated venv."""
    for candidate in ("/usr/bin/python3", "/usr/local/bin/python3", shutil.which("python3", path=os.defpath)):
        if not candidate or not os.path.isfile(candidate):
            continue
        probe = subprocess.run([candidate, "-c", "import skelcore.io"], capture_output=True, env=os.environ)
        if probe.returncode != 0:
            folder = tmp_path / "bin"
            folder.mkdir()
            (folder / "python3").symlink_to(candidate)
            return folder
    pytest.skip("no interpreter on this machine lacks skelcore")


def test_the_samples_axis_method_runs_when_python3_on_path_is_not_ours(tmp_path, monkeypatch):
    """The bug: ``python3 axis_skeleton.py`` ran the system Python ("No module named ..."). With
    ``{python}`` every axis job of resources/compare/samples.toml runs and scores as a straight
    line through each shape should."""
    monkeypatch.setenv("PATH", str(_foreign_python3(tmp_path)))
    m = load_manifest(SAMPLES)  # checks the program: {python} is sys.executable, PATH is not used
    axis = next(x for x in m.methods if x.name == "axis")
    assert axis.command.split()[0] == "{python}"
    assert command_argv(axis.command, "axis", {})[0] == sys.executable

    # the command with python3 in place of {python} fails under this PATH, so the test below can tell the difference
    old = dataclasses.replace(axis, command=axis.command.replace("{python}", "python3"))
    job = next(j for j in make_jobs(m) if j.method.name == "axis" and j.condition.name == "normal")
    rec = run_job(dataclasses.replace(job, method=old))
    assert rec["status"] == "failed" and "No module named" in rec["error"]

    records = {j.shape.name: run_job(j) for j in make_jobs(m) if j.method.name == "axis" and j.condition.name == "normal"}
    assert set(records) == {"cylinder", "torus", "yshape"}
    assert all(r["status"] == "ok" for r in records.values()), {k: r["error"] for k, r in records.items()}
    n_vertices = {k: len(r["arrays"]["curve_vertices"]) for k, r in records.items()}
    assert n_vertices == {"cylinder": 16, "torus": 16, "yshape": 16}  # axis_skeleton.py's polyline
    # the cylinder's principal axis lies inside it; a diameter of the torus crosses its hole
    assert records["cylinder"]["scores"]["boundedness_curve"] > 0.95
    assert records["torus"]["scores"]["boundedness_curve"] < 0.8


def test_a_command_checked_against_path_is_refused_but_python_placeholder_is_not(tmp_path, monkeypatch):
    (tmp_path / "clouds").mkdir()
    io.write_points_ply(tmp_path / "clouds" / "c.ply", shapes.cylinder(200, seed=1).cloud)
    (tmp_path / "empty").mkdir()
    monkeypatch.setenv("PATH", str(tmp_path / "empty"))
    body = """
    [[shapes]]
    path = "clouds/c.ply"
    [[methods]]
    name = "ext"
    kind = "command"
    command = "{prog} tool.py {{in}} {{out_curve}}"
    """
    with pytest.raises(SkelInputError, match="'python3' is not on PATH"):
        load_manifest(manifest(tmp_path, body.format(prog="python3")))
    assert load_manifest(manifest(tmp_path, body.format(prog="{python}"))).methods[0].command.startswith("{python}")


# ---- files methods: scale / offset ---------------------------------------------------------------

SCALE, OFFSET = 0.001, (10.0, -5.0, 2.5)  # a skeleton written in millimetres about another origin


@pytest.fixture(scope="module")
def frames(tmp_path_factory):
    """The true skeletons, and the same skeletons written in another frame (v - OFFSET) / SCALE."""
    root = make_dataset(tmp_path_factory.mktemp("frames"), n=400)
    off = np.asarray(OFFSET)
    for stem in ("cyl", "yshape"):
        pts = io.load_points(root / "skeletons" / f"{stem}_skeletal.ply")
        curve = io.load_curve(root / "skeletons" / f"{stem}_curve.ply")
        io.write_points_ply(root / "skeletons" / f"{stem}_mm_skeletal.ply", (pts - off) / SCALE)
        io.write_curve_ply(root / "skeletons" / f"{stem}_mm_curve.ply", (curve.vertices - off) / SCALE, curve.edges)
    return root


def _mapping_body(scale: str = f"{SCALE}", offset: str = f"{list(OFFSET)}") -> str:
    return f"""
    [evaluation]
    curve_samples = 120
    [[shapes]]
    path = "clouds/*.ply"
    [[methods]]
    name = "truth"
    kind = "files"
    skeletal = "skeletons/{{stem}}_skeletal.ply"
    curve = "skeletons/{{stem}}_curve.ply"
    [[methods]]
    name = "mm_mapped"
    kind = "files"
    skeletal = "skeletons/{{stem}}_mm_skeletal.ply"
    curve = "skeletons/{{stem}}_mm_curve.ply"
    scale = {scale}
    offset = {offset}
    [[methods]]
    name = "mm_as_written"
    kind = "files"
    skeletal = "skeletons/{{stem}}_mm_skeletal.ply"
    curve = "skeletons/{{stem}}_mm_curve.ply"
    """


def test_a_skeleton_in_another_frame_scores_as_the_true_one_once_mapped(frames, tmp_path, capsys):
    m = manifest(frames, _mapping_body())
    res = run_compare(m, tmp_path / "out", Backend("serial"), report=False)
    assert res.summary.failed == 0
    rows = {(r["shape"], r["method"]): r for r in res.rows}
    for shape in ("cyl", "yshape"):
        truth, mapped, raw = rows[shape, "truth"], rows[shape, "mm_mapped"], rows[shape, "mm_as_written"]
        for col in SCORE_COLUMNS:
            assert mapped[col] == pytest.approx(truth[col], rel=1e-6, abs=1e-9, nan_ok=True), (shape, col)
        assert truth["boundedness_curve"] > 0.99 and raw["boundedness_curve"] < 0.01  # unmapped: far away
        assert mapped["key"] != raw["key"]
    # the same map through the command line's flags gives the same scores
    out_json = tmp_path / "cli.json"
    assert main(["evaluate", str(frames / "clouds" / "cyl.ply"), "--skeletal", str(frames / "skeletons" / "cyl_mm_skeletal.ply"),
                 "--curve", str(frames / "skeletons" / "cyl_mm_curve.ply"), "--skeleton-scale", str(SCALE),
                 "--skeleton-offset", *map(str, OFFSET), "--set", "curve_samples=120", "--json", str(out_json),
                 "--quiet"]) == 0
    capsys.readouterr()
    doc = json.loads(out_json.read_text())
    assert rows["cyl", "mm_mapped"]["centeredness_curve"] == pytest.approx(doc["centeredness"]["curve"], rel=1e-9)
    assert rows["cyl", "mm_mapped"]["d_B"] == pytest.approx(doc["topology"]["bottleneck"], rel=1e-9)
    # the stored Evaluation holds the skeleton in the cloud's frame
    from skelcore.compare.finished_run import open_run

    run = open_run(tmp_path / "out")
    ev = run.evaluation(run.find("cyl", "mm_mapped"))
    true_curve = io.load_curve(frames / "skeletons" / "cyl_curve.ply")
    assert np.allclose(ev.curve.curve.vertices, true_curve.vertices, atol=1e-9)


def test_the_mapping_is_part_of_the_job_key_and_the_identity_is_no_mapping(frames):
    def keys(body: str) -> dict[tuple[str, str], str]:
        return {(j.shape.name, j.method.name): j.key for j in make_jobs(load_manifest(manifest(frames, body, "k.toml")))}

    base = keys(_mapping_body())
    assert keys(_mapping_body(scale="0.002"))["cyl", "mm_mapped"] != base["cyl", "mm_mapped"]
    assert keys(_mapping_body(offset="[10.0, -5.0, 2.0]"))["cyl", "mm_mapped"] != base["cyl", "mm_mapped"]
    identity = keys(_mapping_body(scale="1", offset="[0, 0, 0]"))
    unmapped = keys(_mapping_body().replace(f"scale = {SCALE}", "").replace(f"offset = {list(OFFSET)}", ""))
    assert identity["cyl", "mm_mapped"] == unmapped["cyl", "mm_mapped"] != base["cyl", "mm_mapped"]
    assert identity["cyl", "truth"] == base["cyl", "truth"]


@pytest.mark.parametrize("scale, offset, message", [
    ("0", "[0, 0, 0]", "scale must be a finite number > 0, got 0"),
    ("-2.0", "[0, 0, 0]", "scale must be a finite number > 0, got -2.0"),
    ('"2"', "[0, 0, 0]", "scale must be a finite number > 0, got '2'"),
    ("true", "[0, 0, 0]", "scale must be a finite number > 0, got True"),
    ("nan", "[0, 0, 0]", "scale must be a finite number > 0, got nan"),
    ("1", "[1, 2]", "offset must be three finite numbers [x, y, z], got [1, 2]"),
    ("1", '[1, 2, "a"]', "offset must be three finite numbers"),
    ("1", "3", "offset must be three numbers [x, y, z], got 3"),
    ("1", "[1, 2, inf]", "offset must be three finite numbers"),
])
def test_bad_mappings_are_one_line_naming_the_method(frames, tmp_path, capsys, scale, offset, message):
    m = manifest(frames, _mapping_body(scale=scale, offset=offset), "bad.toml")
    assert main(["compare", str(m), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "bad.toml" in err[0] and "method 'mm_mapped'" in err[0] and message in err[0], err
    assert not (tmp_path / "o").exists()


def test_scale_and_offset_belong_to_files_methods_only(frames, capsys, tmp_path):
    body = """
    [[shapes]]
    path = "clouds/*.ply"
    [[methods]]
    name = "b"
    kind = "builtin"
    scale = 2.0
    """
    assert main(["compare", str(manifest(frames, body, "b.toml")), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    assert "unknown key 'scale'" in capsys.readouterr().err
