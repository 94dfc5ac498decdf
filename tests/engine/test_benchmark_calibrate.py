"""``skelcore bench calibrate``: the truth rules, the counting, and a tiny run through the CLI (the
small synthetic suite's Y at 1200 points: intact, spurs, a chord) with its tables, resume, the docs
block and bad input."""

from __future__ import annotations

import csv

import numpy as np
import pytest

from skelcore.benchmark.calibration.calib_tables import DOC_MARKS, fill_docs, outcome, summary_rows
from skelcore.benchmark.calibration.grid import CODES, calibration_tasks
from skelcore.benchmark.calibration.skeletons import Made, World, nodes_only
from skelcore.benchmark.calibration.truth import origin, outside_depth, uncovered_radii
from skelcore.cli.main import main
from skelcore.errors import SkelInputError


def _tube_world() -> World:
    """A straight tube of radius 1 along x from 0 to 10: its axis is the reference."""
    v = np.column_stack([np.linspace(0, 10, 41), np.zeros(41), np.zeros(41)])
    e = np.column_stack([np.arange(40), np.arange(1, 41)])

    def depth(p):
        p = np.asarray(p, float)
        radial = np.hypot(p[:, 1], p[:, 2]) - 1.0
        along = np.maximum(-p[:, 0], p[:, 0] - 10.0)
        return np.maximum(radial, along)
    return World(np.zeros((0, 3)), np.zeros(0), (v, e, np.ones(41)), depth, True)


def test_outside_and_incomplete_truth_read_the_geometry():
    w = _tube_world()
    v, e, _ = w.ref
    intact = Made("intact", v, e)
    assert outside_depth(intact, w, origin(intact, v)) <= 0.0
    assert uncovered_radii(intact, w) == pytest.approx(0.0)
    # a spur 3 radii sideways from the middle: 2 radii out of the tube
    tip = np.array([[5.0, 0.0, 3.0]])
    spur = Made("spurs", np.vstack([v, tip]), np.vstack([e, [[20, 41]]]))
    assert origin(spur, v)[-1] == -1 and outside_depth(spur, w, origin(spur, v)) == pytest.approx(2.0, abs=0.1)
    # half the axis removed: 5 radii of it farther than two radii from what is left, less the 2 covered
    half = Made("truncation", v[:21], e[:20])
    assert uncovered_radii(half, w) == pytest.approx(3.0, abs=0.3)


def test_nodes_only_leaves_no_degree_two_vertex_and_keeps_the_nodes():
    v = np.column_stack([np.linspace(0, 4, 9), np.zeros(9), np.zeros(9)])
    e = np.column_stack([np.arange(8), np.arange(1, 9)])
    nv, ne = nodes_only(v, e)
    assert len(nv) == 2 and ne.tolist() == [[0, 1]]
    assert not (np.bincount(ne.ravel()) == 2).any()


def test_outcome_counts_a_spur_warning_only_where_the_spurs_are():
    row = {"truth_spurious_branches": 1, "fired_spurious_branches": 1, "spurs_located": False}
    assert outcome(row, "spurious_branches") == "fn"
    assert outcome({**row, "spurs_located": True}, "spurious_branches") == "tp"
    assert outcome({"truth_outside": 0, "fired_outside": 1}, "outside") == "fp"
    assert outcome({"truth_outside": None, "fired_outside": 1}, "outside") is None
    s = summary_rows([{"suite": "synthetic", "size": 1200, "condition": "clean", "truth_outside": 1,
                       "fired_outside": 1}] * 3 + [{"suite": "synthetic", "size": 1200, "condition": "clean",
                                                    "truth_outside": 0, "fired_outside": 1}])
    out = next(x for x in s if x["code"] == "outside" and x["condition"] == "all")
    assert (out["tp"], out["fp"], out["precision"]) == (3, 1, 0.75)
    assert 0.0 < out["precision_lo"] < 0.75 < out["precision_hi"] <= 1.0  # Wilson, not the normal interval


def test_the_tuning_neurons_rows_stand_apart_from_the_held_out_ones():
    from skelcore.benchmark.calibration.calib_tables import REAL_TUNING, TUNING_NEURONS, markdown

    base = {"suite": "real", "size": 30000, "condition": "clean", "truth_outside": 0, "fired_outside": 1}
    rows = [{**base, "shape": TUNING_NEURONS[0]}, {**base, "shape": "722817260", "fired_outside": 0}]
    s = [x for x in summary_rows(rows) if x["code"] == "outside" and x["condition"] == "all"]
    by = {x["suite"]: x for x in s}
    assert set(by) == {"real, held-out neurons", REAL_TUNING}
    assert (by["real, held-out neurons"]["tn"], by["real, held-out neurons"]["held_out"]) == (1, True)
    assert (by[REAL_TUNING]["fp"], by[REAL_TUNING]["held_out"]) == (1, False)
    collapse = next(x for x in summary_rows(rows) if x["code"] == "collapse" and x["suite"] == REAL_TUNING)
    assert collapse["held_out"]  # tuned on the synthetic suite alone: the tuning neurons hold it out
    text = markdown(summary_rows(rows))
    assert "| real, tuning neurons 30k |" in text and "tuning data |" in text


def test_unknown_names_are_one_line_errors():
    with pytest.raises(SkelInputError, match="unknown suite"):
        calibration_tasks(["nope"])
    with pytest.raises(SkelInputError, match="unknown skeleton kind"):
        calibration_tasks(["synthetic-small"], kinds=["warts"])
    with pytest.raises(SkelInputError, match="unknown shape"):
        calibration_tasks(["synthetic-small"], shapes=["hammer"])
    with pytest.raises(SkelInputError, match="cannot read"):
        fill_docs("/nonexistent/page.md", "x")


def test_a_tiny_run_counts_hits_and_false_alarms(tmp_path, capsys):
    out = tmp_path / "calib"
    docs = tmp_path / "page.md"
    docs.write_text(f"# Page\n\n{DOC_MARKS[0]}\nold\n{DOC_MARKS[1]}\n\nafter\n", encoding="utf-8")
    args = ["bench", "calibrate", "--out", str(out), "--suite", "synthetic-small", "--shapes", "junction_y",
            "--kinds", "intact", "spurs", "chord_cycle", "--workers", "1", "--quiet", "--docs", str(docs)]
    assert main(args) == 0
    with open(out / "rows.csv", encoding="utf-8") as fh:
        rows = {r["kind"]: r for r in csv.DictReader(fh)}
    assert set(rows) == {"intact", "spurs", "chord_cycle"}
    for code in CODES:
        assert f"truth_{code}" in rows["intact"] and f"fired_{code}" in rows["intact"]
    # the exact Y raises none of its skeleton codes; the spurs and the chord are found where injected
    assert rows["intact"]["truth_spurious_branches"] == "0" and rows["intact"]["fired_spurious_branches"] == "0"
    assert rows["spurs"]["truth_spurious_branches"] == "1" and rows["spurs"]["spurs_located"] == "True"
    assert rows["chord_cycle"]["truth_spurious_cycles"] == "1" and rows["chord_cycle"]["fired_spurious_cycles"] == "1"
    table = (out / "calibration.md").read_text(encoding="utf-8")
    assert "| `spurious_branches` | synthetic 1200 | 1 | 0 | 0 | 2 |" in table
    page = docs.read_text(encoding="utf-8")
    assert "\nold\n" not in page and "| `spurious_cycles` |" in page and page.endswith("\nafter\n")
    # a rerun keeps the task; a folder of another kind is refused in one line, exit 2
    assert main(args[:-2]) == 0
    assert "1 already done" in capsys.readouterr().out
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "notes.txt").write_text("mine")
    assert main(["bench", "calibrate", "--out", str(tmp_path / "other"), "--suite", "synthetic-small"]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1
    with pytest.raises(SkelInputError, match="markers"):
        fill_docs(tmp_path / "other" / "notes.txt", "x")
