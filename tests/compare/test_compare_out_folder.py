"""``skelcore compare --out DIR`` never writes into a user's folder: DIR must be new, empty or
one of our runs, recognised by its ``.skelscope-run`` marker (skelcore/compare/run_marker.py), not by
its file names; anything else is one line and exit 2 before a file is touched, unless ``--force``."""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import pytest

from compare_helpers import make_dataset, manifest
from skelcore.cli import main
from skelcore.compare import Backend, run_compare
from skelcore.compare.results_csv import COLUMNS
from skelcore.compare.run_marker import MARKER, claim_run_folder, is_run_folder, read_marker
from skelcore.errors import SkelInputError

BODY = """
[evaluation]
curve_samples = 60
[[shapes]]
path = "clouds/*.ply"
[[methods]]
name = "truth"
kind = "files"
curve = "skeletons/{stem}_curve.ply"
"""
NOTES = "my own notes: do not lose\n"
USERS_CSV = "sample,my_score\na,0.5\n"


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    root = make_dataset(tmp_path_factory.mktemp("outdir"), n=300)
    return root, manifest(root, BODY)


def _snapshot(folder: Path) -> dict[str, tuple[bytes, int]]:
    return {str(p.relative_to(folder)): (p.read_bytes() if p.is_file() else b"", p.stat().st_mtime_ns)
            for p in sorted(folder.rglob("*"))}


def _precious(parent: Path) -> Path:
    folder = parent / "precious"
    folder.mkdir()
    (folder / "results.csv").write_text(USERS_CSV)
    (folder / "notes.txt").write_text(NOTES)
    return folder


def _compare(m: Path, out: Path, *extra: str) -> int:
    return main(["compare", str(m), "--out", str(out), "--jobs", "1", "--no-report", "--quiet", *extra])


def test_a_users_folder_with_a_results_csv_is_refused_in_one_line_and_left_untouched(data, tmp_path, capsys):
    _root, m = data
    precious = _precious(tmp_path)
    before = _snapshot(precious)
    assert _compare(m, precious) == 2
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert len(err) == 1 and str(precious) in err[0] and "not a skelcore compare run" in err[0]
    assert "--force" in err[0] and "'results.csv'" in err[0]
    assert captured.out == ""
    assert _snapshot(precious) == before  # same files, same bytes, not even rewritten
    with pytest.raises(SkelInputError, match="--force"):
        run_compare(m, precious, Backend("serial"), report=False)  # the Python API refuses too
    assert _snapshot(precious) == before


def test_force_writes_into_it_and_marks_it_so_later_runs_resume(data, tmp_path, capsys):
    _root, m = data
    precious = _precious(tmp_path)
    assert _compare(m, precious, "--force") == 0
    assert (precious / "notes.txt").read_text() == NOTES  # only our file names are written
    assert (precious / "results.csv").read_text().splitlines()[0].split(",")[:2] == list(COLUMNS[:2])
    doc = read_marker(precious)
    assert doc["kind"] == "compare" and doc["manifest"] == str(m.resolve())
    capsys.readouterr()
    assert _compare(m, precious) == 0  # now one of our runs: resumed without --force
    assert "2 jobs: 2 already done, 0 ran ok" in capsys.readouterr().out


def test_an_empty_existing_folder_becomes_a_run(data, tmp_path):
    _root, m = data
    empty = tmp_path / "empty"
    empty.mkdir()
    res = run_compare(m, empty, Backend("serial"), report=False)
    assert res.summary.ok == 2 and is_run_folder(empty, "compare")
    assert (empty / "results.csv").is_file() and (empty / "index.json").is_file()


def test_a_run_resumes_and_keeps_its_marker(data, tmp_path):
    _root, m = data
    out = tmp_path / "new" / "run"  # parents are created
    first = run_compare(m, out, Backend("serial"), report=False)
    marker = (out / MARKER).read_bytes()
    assert first.summary.ok == 2 and json.loads(marker)["skelscope_run"] == 1
    again = run_compare(m, out, Backend("serial"), report=False)
    assert again.summary.skipped == 2 and again.summary.ok == 0
    assert (out / MARKER).read_bytes() == marker


def test_a_run_made_before_the_marker_is_refused_until_forced_once(data, tmp_path, capsys):
    """Its index.json and jobs/ are file names anyone could have: the user confirms it once."""
    _root, m = data
    out = tmp_path / "old"
    run_compare(m, out, Backend("serial"), report=False)
    (out / MARKER).unlink()
    before = _snapshot(out)
    assert _compare(m, out) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "made before skelcore marked its runs" in err[0] and "--force once" in err[0]
    assert _snapshot(out) == before
    assert _compare(m, out, "--force") == 0
    assert "2 already done, 0 ran ok" in capsys.readouterr().out  # resumed: nothing recomputed
    assert is_run_folder(out, "compare")
    assert _compare(m, out) == 0


@pytest.mark.parametrize("what, message", [
    ("file", "is a file, not a folder"),
    ("bench", "is a skelcore 'bench' run, not a compare run"),
    ("garbled", f"unreadable {MARKER} marker"),
    ("names", "no .skelscope-run marker; it holds 'leaderboard.md', 'report.html', 'results.csv'): choose a new"),
])
def test_other_folders_are_refused_by_the_marker_not_the_file_names(data, tmp_path, capsys, what, message):
    _root, m = data
    out = tmp_path / "out"
    if what == "file":
        out.write_text("x")
    else:
        out.mkdir()
        if what == "bench":
            (out / MARKER).write_text(json.dumps({"skelscope_run": 1, "kind": "bench"}))
        elif what == "garbled":
            (out / MARKER).write_text("not json")
        else:  # our output names, without our marker
            for name in ("leaderboard.md", "report.html", "results.csv"):
                (out / name).write_text("mine\n")
    before = _snapshot(out) if out.is_dir() else out.read_bytes()
    assert _compare(m, out) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err
    assert (_snapshot(out) if out.is_dir() else out.read_bytes()) == before


def test_the_claim_states(tmp_path):
    """The module the bench commands reuse: created / resumed / forced, and the kind is kept apart."""
    folder = tmp_path / "a"
    assert claim_run_folder(folder, "bench").state == "created"
    assert claim_run_folder(folder, "bench").state == "resumed"
    with pytest.raises(SkelInputError, match="is a skelcore 'bench' run, not a compare run"):
        claim_run_folder(folder, "compare")
    user = tmp_path / "b"
    user.mkdir()
    (user / "x.txt").write_text("mine")
    with pytest.raises(SkelInputError, match=r"holds 'x\.txt'"):
        claim_run_folder(user, "bench")
    assert claim_run_folder(user, "bench", force=True).state == "forced"
    assert (user / "x.txt").read_text() == "mine" and is_run_folder(user, "bench") and not is_run_folder(user, "compare")


def test_the_viewers_run_reader_writes_no_marker(data, tmp_path):
    """Opening a run (File > Open comparison run) reads: an old run stays as it was."""
    from skelcore.compare.finished_run import open_run

    _root, m = data
    out = tmp_path / "run"
    run_compare(m, out, Backend("serial"), report=False)
    (out / MARKER).unlink()
    before = _snapshot(out)
    run = open_run(out)
    for job in run.jobs:
        run.evaluation(job)
    assert _snapshot(out) == before and not os.path.exists(out / MARKER)
    shutil.rmtree(out)
