"""skelcore.experiments.study: variants, tables, files, the user's skeleton command and the CLI."""

from __future__ import annotations

import csv
import io
import json
import shlex
import sys

import numpy as np
import pytest

from skelcore import shapes
from skelcore.cli import main
from skelcore.skeleton.degrade import voxel_grid_average
from skelcore.errors import Cancelled, SkelInputError
from skelcore.io import load_cloud, load_curve, load_points, write_points_ply
from skelcore.experiments.study import run_study


@pytest.fixture(scope="module")
def cloud() -> np.ndarray:
    return shapes.cylinder(1200, seed=21).cloud


@pytest.fixture(scope="module")
def study(cloud, tmp_path_factory):
    out = tmp_path_factory.mktemp("study")
    return run_study(cloud, noise=0.05, noise_model="isotropic", sparse=400, seed=1, out_dir=out, name="cyl"), out


def test_study_has_the_papers_three_rows(study, cloud):
    result, _out = study
    assert [r.name for r in result.rows] == ["normal", "noise", "sparse"]
    assert [r.label for r in result.rows] == ["1200 pts", "5% noise", "400 pts"]
    assert len(result.rows[1].cloud) == 1200 and not np.allclose(result.rows[1].cloud, cloud)
    assert len(result.rows[2].cloud) == 400
    for row in result.rows:
        assert row.skeletal.shape == row.cloud.shape  # each variant is skeletonized on its own
        s = row.scores()
        assert 0 <= s["boundedness_skeletal"] <= 1 and s["d_B"] >= s["d_Wp"] >= 0


def test_every_variant_is_scored_against_its_own_cloud(study):
    result, _out = study
    for row in result.rows:
        assert row.evaluation.cloud is row.cloud or np.array_equal(row.evaluation.cloud, row.cloud)


def test_markdown_table_cells_are_skeletal_slash_curve(study):
    result, _out = study
    lines = result.to_markdown().splitlines()
    assert lines[0].split("|")[1].strip() == "shape"
    assert len(lines) == 2 + 3
    normal = [c.strip() for c in lines[2].strip("|").split("|")]
    assert normal[0] == "cyl (1200 pts)"
    s = result.rows[0].scores()
    assert normal[1] == f"{s['d_B']:.4f}/{s['d_Wp']:.4f}"
    assert normal[2] == f"{s['boundedness_skeletal']:.3f}/{s['boundedness_curve']:.3f}"


def test_csv_and_latex_carry_the_same_numbers(study):
    result, out = study
    rows = list(csv.DictReader(io.StringIO((out / "study.csv").read_text())))
    assert [r["variant"] for r in rows] == ["normal", "noise", "sparse"]
    for row, parsed in zip(result.rows, rows):
        for key, value in row.scores().items():
            np.testing.assert_array_equal(float(parsed[key]), value)  # full precision, nan == nan
    tex = (out / "study.tex").read_text()
    assert tex.startswith("\\begin{tabular}") and "5\\% noise" in tex and tex.count("\\\\") == 4


def test_every_variants_files_are_written_and_load_back(study):
    result, out = study
    for row in result.rows:
        assert np.allclose(load_cloud(out / f"{row.name}_cloud.ply"), row.cloud)
        assert np.allclose(load_points(out / f"{row.name}_skeletal.ply"), row.skeletal)
        curve = load_curve(out / f"{row.name}_curve.ply")
        assert curve.n_edges == row.curve.n_edges
        doc = json.loads((out / f"{row.name}_evaluation.json").read_text())
        assert doc["boundedness"]["skeletal"] == pytest.approx(row.scores()["boundedness_skeletal"])


def test_grid_row_is_the_voxel_grid_average_of_the_input(cloud):
    result = run_study(cloud, noise=0, grid=0.3, seed=0)
    assert [r.name for r in result.rows] == ["normal", "sparse"]
    assert len(result.rows[1].cloud) == len(voxel_grid_average(cloud, 0.3)[0])


def test_sparse_and_grid_together_are_refused(cloud):
    with pytest.raises(SkelInputError, match="not both"):
        run_study(cloud, sparse=100, grid=0.1)


def test_the_same_seed_repeats_the_study(cloud):
    a = run_study(cloud, noise=0.05, sparse=300, seed=4)
    b = run_study(cloud, noise=0.05, sparse=300, seed=4)
    assert a.to_csv() == b.to_csv()


def test_user_skeleton_command_is_run_per_variant(cloud, tmp_path):
    cmd = (f"{shlex.quote(sys.executable)} -m skelcore skeletonize {{in}} "
           "--out-skeletal {out_skeletal} --out-curve {out_curve} --raw --quiet")  # the study's cao is raw
    ours = run_study(cloud, noise=0, sparse=500, seed=2)
    theirs = run_study(cloud, noise=0, sparse=500, seed=2, skeleton_cmd=cmd, out_dir=tmp_path)
    # the built-in skeletonizer run as an external program gives the same table
    assert theirs.to_csv() == ours.to_csv()
    assert (tmp_path / "sparse_curve.ply").is_file()


def test_curve_only_command_leaves_the_skeletal_cells_empty(cloud, tmp_path):
    script = tmp_path / "line.py"
    script.write_text(
        "import sys, numpy as np\n"
        "from skelcore.io import load_cloud, write_curve_ply\n"
        "c = load_cloud(sys.argv[1])\n"
        "z = np.linspace(c[:, 2].min(), c[:, 2].max(), 9)\n"
        "v = np.column_stack([np.zeros(9), np.zeros(9), z])\n"
        "write_curve_ply(sys.argv[2], v, np.column_stack([np.arange(8), np.arange(1, 9)]))\n"
    )
    cmd = f"{shlex.quote(sys.executable)} {shlex.quote(str(script))} {{in}} {{out_curve}}"
    result = run_study(cloud, noise=0, sparse=600, seed=0, skeleton_cmd=cmd)
    row = result.table()[1]
    assert row[1] == "-/-"
    assert row[2].startswith("-/")
    assert result.rows[0].scores()["boundedness_curve"] == pytest.approx(1.0)


@pytest.mark.parametrize(
    "cmd, message",
    [
        ("echo {out_curve}", r"\{in\}"),
        ("echo {in}", "out_skeletal"),
        (f"{shlex.quote(sys.executable)} -c 'import sys; sys.exit(3)' {{in}} {{out_curve}}", "status 3"),
        ("echo {in} {out_curve}", "did not write"),
        ("/no/such/program {in} {out_curve}", "could not start"),
    ],
)
def test_bad_skeleton_commands_are_input_errors(cloud, cmd, message):
    with pytest.raises(SkelInputError, match=message):
        run_study(cloud, noise=0, sparse=600, skeleton_cmd=cmd)


def test_cancel_stops_the_study(cloud):
    with pytest.raises(Cancelled):
        run_study(cloud, cancel=lambda: True)


def test_progress_reaches_one_and_names_the_variant(cloud):
    seen = []
    run_study(cloud, noise=0, sparse=600, progress=lambda f, s: seen.append((f, s)))
    assert seen[-1][0] == pytest.approx(1.0)
    assert any(s.startswith("sparse:") for _, s in seen)
    fractions = [f for f, _ in seen]
    assert fractions == sorted(fractions)


def test_cli_study_prints_the_table_and_writes_files(cloud, tmp_path, capsys):
    src = tmp_path / "cyl.ply"
    write_points_ply(src, cloud)
    out = tmp_path / "out"
    rc = main(["study", str(src), "--sparse", "500", "--noise", "0.02", "--seed", "3", "--out", str(out), "--quiet"])
    text = capsys.readouterr().out
    assert rc == 0
    assert "| cyl (1200 pts)" in text and "| cyl (2% noise)" in text and "| cyl (500 pts)" in text
    assert (out / "study.md").read_text() in text


def test_cli_study_input_error_is_one_line_and_exit_2(tmp_path, capsys):
    rc = main(["study", str(tmp_path / "missing.ply")])
    err = capsys.readouterr().err
    assert rc == 2
    assert len(err.strip().splitlines()) == 1 and "missing.ply" in err


def test_cli_skeletonize_writes_loadable_skeletons(cloud, tmp_path, capsys):
    src = tmp_path / "cyl.ply"
    write_points_ply(src, cloud)
    rc = main(["skeletonize", str(src), "--out-skeletal", str(tmp_path / "s.ply"),
               "--out-curve", str(tmp_path / "c.ply"), "--quiet", "--method", "skelscope"])
    assert rc == 0
    assert load_points(tmp_path / "s.ply").shape == cloud.shape
    assert load_curve(tmp_path / "c.ply").degrees().max() <= 2
    # the default, the toolbox's algorithm, writes the same kinds of files
    assert main(["skeletonize", str(src), "--out-curve", str(tmp_path / "c2.ply"), "--quiet"]) == 0
    assert "(cao)" in capsys.readouterr().out
    assert load_curve(tmp_path / "c2.ply").n_vertices >= 2
    assert main(["skeletonize", str(src)]) == 2
