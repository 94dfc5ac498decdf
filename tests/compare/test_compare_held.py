"""The held ground-truth scores in compare (docs/compare.md "Ground truth", docs/metrics.md 5.3.1): on
a real suite's case (``bench make --suite real-small``: a traced neuron sampled at 30k points, its
compare.toml naming the case's facts file as ``reference_facts``), ``skelcore compare`` gives held
precision / recall / F1 beside the plain ones in results.csv, the job's record, the leaderboard (text,
CSV and report.html, looked at in headless Chromium), equal to the ground truth computed directly;
a facts file that does not match its reference is one line naming it, exit 2, before any job runs.
The same folder, made once here, is the check of ``bench make --suite real-small`` itself: the files
compare accepts, the case's record and facts, a rerun that keeps the case."""

from __future__ import annotations

import contextlib
import csv
import io
import json
import re
import shutil
import sys

import numpy as np
import pytest

from headless_chromium import browser
from skelcore import Params
from skelcore.benchmark.neurons import NEURON_IDS, load_neuron, read_outside_radii, surface_distance
from skelcore.cli import main
from skelcore.compare.jobs import make_jobs
from skelcore.compare.manifest import load_manifest
from skelcore.io import load_cloud, load_curve, write_curve_ply
from skelcore.metrics.ground_truth import ground_truth

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

CASE = f"{NEURON_IDS[0]}_30k__clean"
FACTS = f"truth/{NEURON_IDS[0]}_gt_facts.csv"
HELD = ("gt_held_precision", "gt_held_recall", "gt_held_f1")
PLAIN = ("gt_precision", "gt_recall", "gt_f1")
#: the suite's manifest with its built-in methods replaced by one precomputed curve (fast): the traced
#: skeleton less its nodes more than one radius outside the mesh (held F1 above the plain one)
METHOD = """[[methods]]
name = "held_part"
kind = "files"
curve = "skeletons/{stem}_held_part.ply"

[[conditions]]
name = "normal"
"""


def _manifest(folder, name: str = "held.toml", facts_line: str | None = None) -> str:
    text = (folder / "compare.toml").read_text()
    shapes = text[text.index("[[shapes]]"):]
    if facts_line is not None:
        shapes = re.sub(r"reference_facts = .*\n", facts_line, shapes)
    (folder / name).write_text(METHOD + "\n" + shapes)
    return str(folder / name)


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    """``bench make --suite real-small`` into a fresh folder: the folder and what the command printed."""
    folder = tmp_path_factory.mktemp("held") / "real"
    with contextlib.redirect_stdout(io.StringIO()) as printed:
        assert main(["bench", "make", str(folder), "--suite", "real-small", "--quiet"]) == 0
    return folder, printed.getvalue()


@pytest.fixture(scope="module")
def suite(made):
    """The made folder with the precomputed held-part curve under skeletons/."""
    folder, _printed = made
    ref = load_curve(folder / "truth" / f"{CASE}_reference.ply")
    held = read_outside_radii(folder / FACTS, ref.n_vertices) <= Params().gt_held_radii
    (folder / "skeletons").mkdir()
    write_curve_ply(folder / "skeletons" / f"{CASE}_held_part.ply", ref.vertices,
                    ref.edges[held[ref.edges].all(axis=1)])
    return folder


@pytest.fixture(scope="module")
def run(suite):
    out = suite / "out"
    assert main(["compare", _manifest(suite), "--out", str(out), "--jobs", "1", "--quiet"]) == 0
    with open(out / "results.csv", newline="") as fh:
        (row,) = list(csv.DictReader(fh))
    (rec,) = [json.loads(p.read_text()) for p in (out / "jobs").glob("*.json")]
    return out, row, rec



def test_bench_make_real_small_writes_a_folder_compare_accepts(made, tmp_path, capsys):
    from skelcore.compare.manifest import parse_manifest

    folder, printed = made
    assert "1 cases of the 'real-small' suite" in printed and "1 made, 0 already there" in printed
    name = f"{NEURON_IDS[0]}_30k__clean"
    doc = tomllib.loads((folder / "compare.toml").read_text())
    assert [s["name"] for s in doc["shapes"]] == [name] and doc["shapes"][0]["tree"] is True
    m = parse_manifest(doc, str(folder / "compare.toml"))  # references checked: files, frame, no cycle
    assert [s.name for s in m.shapes] == [name]
    rec = json.loads((folder / "cases" / f"{name}.json").read_text())
    assert rec["points"] == 30000 and rec["curve_skeleton"] == "traced" and rec["gt_facts"]["closed"] is True
    assert 0.45 < rec["gt_facts"]["outside_fraction"] < 0.55
    from skelcore.benchmark import read_reference

    ref = read_reference(folder / "truth" / f"{name}_reference.ply")
    neuron = load_neuron(NEURON_IDS[0])
    assert np.array_equal(ref.curve.vertices, neuron.skeleton.vertices) and np.allclose(ref.radius, neuron.skeleton.radius)
    cloud = load_cloud(folder / "clouds" / f"{name}.ply")
    assert np.allclose(surface_distance(neuron.mesh, cloud[:200]), 0.0, atol=1e-6)  # on the mesh
    with open(folder / "truth" / f"{NEURON_IDS[0]}_gt_facts.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == len(neuron.skeleton.vertices) and rows[0]["swc_id"] == "1"
    inside = np.array([int(r["inside"]) for r in rows], bool)
    assert np.mean(~inside) == pytest.approx(rec["gt_facts"]["outside_fraction"], abs=1e-6)
    assert all(float(r["outside_by"]) == 0 for r in rows if r["inside"] == "1")
    # a rerun keeps the case; sizes only for the real suites
    assert main(["bench", "make", str(folder), "--suite", "real-small", "--quiet"]) == 0
    assert "0 made, 1 already there" in capsys.readouterr().out
    assert main(["bench", "make", str(tmp_path / "gen"), "--suite", "small", "--sizes", "2000", "--quiet"]) == 2
    assert "sizes apply to the real suites only" in capsys.readouterr().err


def test_the_suites_manifest_names_the_facts(suite):
    text = (suite / "compare.toml").read_text()
    assert f'reference_facts = "{FACTS}"' in text
    (shape,) = load_manifest(_manifest(suite)).shapes
    assert shape.reference_facts == str(suite / FACTS)


def test_results_and_record_carry_the_held_scores_of_the_ground_truth(suite, run):
    out, row, rec = run
    cloud = load_cloud(suite / "clouds" / f"{CASE}.ply")
    ref = load_curve(suite / "truth" / f"{CASE}_reference.ply")
    curve = load_curve(suite / "skeletons" / f"{CASE}_held_part.ply")
    want = ground_truth(curve, ref, cloud, Params(), outside_radii=read_outside_radii(suite / FACTS, ref.n_vertices))
    assert row["status"] == "ok" and rec["status"] == "ok"
    for key, value in zip(PLAIN + HELD, (want.precision, want.recall, want.f1,
                                         want.held_precision, want.held_recall, want.held_f1)):
        assert row[key] == repr(float(value)), key  # the same bits
        assert rec["scores"][key] == float(value), key
    assert float(row["gt_held_f1"]) > float(row["gt_f1"]) + 0.02  # the part the mesh cannot show left out
    assert float(row["gt_held_recall"]) > float(row["gt_recall"])
    gt = rec["evaluation"]["ground_truth"]
    assert gt["held_nodes"][1] == ref.n_vertices and gt["held_radii"] == Params().gt_held_radii


def test_the_leaderboard_shows_held_beside_plain(run):
    out, row, _rec = run
    md = (out / "leaderboard.md").read_text()
    head = md.splitlines()[0]
    assert head.index("gt_f1 ↑") < head.index("gt_held_precision ↑") < head.index("gt_held_f1 ↑") \
        < head.index("gt_junction_precision")
    with open(out / "leaderboard.csv", newline="") as fh:
        (entry,) = list(csv.DictReader(fh))
    for key in HELD:
        assert float(entry[f"{key}_mean"]) == float(row[key]) and entry[f"{key}_std"] == "0.0"


def test_report_html_shows_the_held_scores_in_chromium(run, tmp_path):
    out, row, _rec = run
    dom = browser(tmp_path, "--dump-dom", (out / "report.html").resolve().as_uri())
    assert dom.returncode == 0, dom.stderr[-500:]
    page = dom.stdout
    loaded = re.search(r'data-images="(\d+)/(\d+)"', page)
    assert loaded and loaded.group(1) == loaded.group(2), "the page's images did not all load"
    f1 = f"{float(row['gt_held_f1']):.3f}"
    assert re.search(r"<th title=\"held F1, fraction; higher is better\">held F1 ↑</th>", page)
    assert f"held F1 {f1}" in page  # the job's ground-truth line beside its pictures
    assert re.search(rf"<td[^>]*>{f1}†? ± 0.000</td>", page)  # the leaderboard's cell (a defect marked †)


def test_the_job_key_follows_the_facts_bytes(suite, tmp_path):
    m = load_manifest(_manifest(suite))
    without = load_manifest(_manifest(suite, "plain.toml", facts_line=""))
    assert without.shapes[0].reference_facts is None
    assert make_jobs(m)[0].key != make_jobs(without)[0].key


@pytest.mark.parametrize("facts_line, message", [
    ('reference_facts = "truth/short_facts.csv"\n',
     f"reference_facts truth/short_facts.csv: the facts have {{n}} rows for a reference of {{m}} vertices"),
    ('reference_facts = "truth/none.csv"\n', "reference_facts truth/none.csv not found"),
    ('reference_facts = "clouds/{stem}.ply"\n', f"reference_facts clouds/{CASE}.ply: not a facts file"),
    ("reference_facts = 3\n", "reference_facts must be a file path or a template with {stem}"),
])
def test_a_facts_file_that_does_not_match_is_one_line_and_nothing_runs(suite, tmp_path, capsys, facts_line,
                                                                        message):
    lines = (suite / FACTS).read_text().splitlines(keepends=True)
    (suite / "truth" / "short_facts.csv").write_text("".join(lines[:-1]))  # one node fewer than the reference
    out = tmp_path / "out"
    code = main(["compare", _manifest(suite, "bad.toml", facts_line), "--out", str(out), "--quiet"])
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1 and "bad.toml" in err and "shapes[0]" in err, err
    assert message.replace("{n}", str(len(lines) - 2)).replace("{m}", str(len(lines) - 1)) in err, err
    assert not out.exists()


def test_facts_without_a_reference_are_refused(suite, capsys):
    text = (suite / "compare.toml").read_text()
    shapes = re.sub(r"reference = .*\n", "", text[text.index("[[shapes]]"):])
    (suite / "noref.toml").write_text(METHOD + "\n" + shapes)
    assert main(["compare", str(suite / "noref.toml"), "--out", str(suite / "noref_out"), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "reference_facts describes the reference's vertices: give reference too" in err, err
    shutil.rmtree(suite / "noref_out", ignore_errors=True)
