"""The skelcore command line, end to end on files."""

import csv
import json
import subprocess
import sys

import numpy as np
import pytest

from skelcore import shapes
from skelcore.cli import main
from skelcore.io import write_curve_ply, write_points_ply


@pytest.fixture(scope="module")
def sample(tmp_path_factory):
    d = tmp_path_factory.mktemp("sample")
    sh = shapes.y_shape(1500, seed=11)
    write_points_ply(d / "cloud.ply", sh.cloud)
    write_points_ply(d / "skel.ply", sh.skeletal)
    write_curve_ply(d / "curve.ply", sh.curve_vertices, sh.curve_edges)
    write_points_ply(d / "short.ply", sh.cloud[:10])
    return d, sh


def run(*argv):
    return main([str(a) for a in argv])


def test_evaluate_prints_the_papers_table(sample, capsys):
    d, _ = sample
    assert run("evaluate", d / "cloud.ply", "--skeletal", d / "skel.ply", "--curve", d / "curve.ply") == 0
    out = capsys.readouterr().out
    for row in ("d_B / d_Wp", "boundedness", "centeredness", "smoothness", "skeletal points", "curve skeleton"):
        assert row in out
    assert "n=1500" in out and "eps*" in out


def test_json_document_has_every_section(sample, tmp_path):
    d, sh = sample
    out = tmp_path / "r.json"
    assert run("evaluate", d / "cloud.ply", "--skeletal", d / "skel.ply", "--curve", d / "curve.ply", "--json", out) == 0
    doc = json.loads(out.read_text())
    assert set(doc) >= {"skelcore_version", "params", "inputs", "topology", "boundedness", "centeredness", "smoothness", "timings_s", "counts"}
    assert doc["inputs"]["cloud"]["n_points"] == len(sh.cloud)
    assert doc["inputs"]["curve"]["n_edges"] == len(sh.curve_edges)
    assert set(doc["topology"]) == {"bottleneck", "wasserstein", "eps_star", "n_bars"}
    assert doc["params"]["boundedness_estimator"] == "rays"
    assert 0 <= doc["boundedness"]["skeletal"] <= 1


def test_json_is_null_where_an_input_was_not_given(sample, tmp_path):
    d, _ = sample
    out = tmp_path / "r.json"
    assert run("evaluate", d / "cloud.ply", "--curve", d / "curve.ply", "--json", out) == 0
    doc = json.loads(out.read_text())
    assert doc["inputs"]["skeletal"] is None and doc["topology"] is None
    assert doc["boundedness"]["skeletal"] is None and doc["boundedness"]["curve"] is not None


def test_per_point_and_barcode_files(sample, tmp_path):
    d, sh = sample
    prefix = tmp_path / "pp"
    bars = tmp_path / "bars.csv"
    assert run("evaluate", d / "cloud.ply", "--skeletal", d / "skel.ply", "--curve", d / "curve.ply",
               "--per-point", prefix, "--barcodes", bars) == 0
    with open(f"{prefix}_skeletal.csv") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["index", "x", "y", "z", "boundedness", "centeredness", "smoothness", "defects"]  # + the diagnostics' column
    assert {r[7] for r in rows[1:]} == {""}  # the true skeletal set: no point outside
    assert len(rows) == len(sh.cloud) + 1
    np.testing.assert_allclose([float(v) for v in rows[1][1:4]], sh.skeletal[0], rtol=1e-12)
    with open(f"{prefix}_curve_vertices.csv") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["vertex", "x", "y", "z", "degree", "smoothness", "branch", "defects"]  # + the diagnostics' columns
    junction = [r for r in rows[1:] if r[4] == "3"]
    assert junction and junction[0][5] == "nan"
    with open(f"{prefix}_curve_samples.csv") as fh:
        assert next(csv.reader(fh)) == ["sample", "edge", "t", "x", "y", "z", "boundedness", "centeredness", "branch",
                                        "defects"]
    with open(bars) as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["diagram", "birth", "death"]
    assert {r[0] for r in rows[1:]} == {"cloud", "skeletal"}
    assert sum(1 for r in rows[1:] if r[2] == "inf") == 2


def test_export_ply_writes_coloured_files(sample, tmp_path):
    from plyfile import PlyData

    d, _ = sample
    out = tmp_path / "ply"
    assert run("evaluate", d / "cloud.ply", "--skeletal", d / "skel.ply", "--curve", d / "curve.ply", "--export-ply", out) == 0
    files = sorted(p.name for p in out.glob("*.ply"))
    assert files, "no PLY written"
    for name in files:
        ply = PlyData.read(str(out / name))
        names = {p.name for p in ply["vertex"].properties}
        assert {"x", "y", "z", "red", "green", "blue"} <= names
    curve_files = [n for n in files if "curve" in n and "sample" not in n]
    assert curve_files and "edge" in {e.name for e in PlyData.read(str(out / curve_files[0])).elements}


@pytest.mark.parametrize(
    "argv, fragment",
    [
        (["evaluate", "{d}/missing.ply", "--curve", "{d}/curve.ply"], "missing.ply"),
        (["evaluate", "{d}/cloud.ply"], "nothing to evaluate"),
        (["evaluate", "{d}/cloud.ply", "--curve", "{d}/curve.ply", "--set", "nope=1"], "unknown parameter"),
        (["evaluate", "{d}/cloud.ply", "--skeletal", "{d}/short.ply", "--skeletal-index", "{d}/missing.txt"],
         "missing.txt"),
        (["evaluate", "{d}/cloud.ply", "--curve", "{d}/curve.ply", "--json", "{d}/cloud.ply"], "overwrite"),
    ],
)
def test_input_errors_exit_2_with_one_line(sample, capsys, argv, fragment):
    d, _ = sample
    before = (d / "cloud.ply").read_bytes()
    assert run(*[a.format(d=d) for a in argv]) == 2
    err = capsys.readouterr().err.strip()
    assert fragment in err and len(err.splitlines()) == 1
    assert (d / "cloud.ply").read_bytes() == before


def test_console_entry_point_runs_as_a_module():
    proc = subprocess.run([sys.executable, "-m", "skelcore", "--help"], capture_output=True, text=True)
    assert proc.returncode == 0 and "evaluate" in proc.stdout
