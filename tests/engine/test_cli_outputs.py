"""Every output option with a path that cannot be written: one line naming it, exit 2, no traceback,
checked before the work (evaluate, study, skeletonize)."""

import subprocess
import sys

import pytest

from skelcore import shapes
from skelcore.cli import main
from skelcore.io import write_curve_ply, write_points_ply


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("out")
    sh = shapes.y_shape(600, seed=2)
    write_points_ply(d / "cloud.ply", sh.cloud)
    write_points_ply(d / "skel.ply", sh.skeletal)
    write_curve_ply(d / "curve.ply", sh.curve_vertices, sh.curve_edges)
    (d / "afile").write_text("not a folder")
    return d


EVAL = ["evaluate", "{d}/cloud.ply", "--skeletal", "{d}/skel.ply", "--curve", "{d}/curve.ply", "--quiet"]


@pytest.mark.parametrize(
    "argv, fragment",
    [
        (EVAL + ["--json", "{d}/afile/x.json"], "afile is a file, not a folder"),
        (EVAL + ["--per-point", "{d}/afile/pp"], "afile is a file, not a folder"),
        (EVAL + ["--barcodes", "{d}/afile/b.csv"], "afile is a file, not a folder"),
        (EVAL + ["--export-ply", "{d}/afile/ply"], "afile is a file, not a folder"),
        (EVAL + ["--export-ply", "{d}/afile"], "output folder is a file"),
        (EVAL + ["--json", "{d}/missing/x.json"], "output folder does not exist"),
        (EVAL + ["--json", "{d}"], "is a folder, not a file"),
        (EVAL + ["--json", "{d}/curve.ply"], "refusing to overwrite an input file"),
        (["study", "{d}/cloud.ply", "--out", "{d}/afile/study", "--quiet"], "afile is a file, not a folder"),
        (["skeletonize", "{d}/cloud.ply", "--out-skeletal", "{d}/afile/s.ply", "--quiet"], "afile is a file"),
        (["skeletonize", "{d}/cloud.ply", "--out-curve", "{d}/missing/c.ply", "--quiet"], "does not exist"),
    ],
)
def test_unwritable_outputs_are_one_line_exit_2(files, capsys, argv, fragment):
    assert main([a.format(d=files) for a in argv]) == 2
    cap = capsys.readouterr()
    err = cap.err.strip()
    assert len(err.splitlines()) == 1 and fragment in err and "Traceback" not in err
    assert "metric" not in cap.out  # refused before the evaluation ran


def test_export_ply_under_a_file_as_a_process_has_no_traceback(files):
    proc = subprocess.run(
        [sys.executable, "-m", "skelcore", *[a.format(d=files) for a in EVAL], "--export-ply", f"{files}/afile/x"],
        capture_output=True, text=True,
    )
    assert proc.returncode == 2 and len(proc.stderr.strip().splitlines()) == 1 and "Traceback" not in proc.stderr
