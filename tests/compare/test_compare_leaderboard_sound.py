"""The leaderboard over the cases where every method is sound (skelcore.compare.leaderboard
.build_sound_leaderboard): which cases it keeps, which methods it leaves out, that its means are the
plain means over those cases and that it ranks them; its files and its place in report.html."""

from __future__ import annotations

import math

import numpy as np

from skelcore.compare.job_store import Store
from skelcore.compare.leaderboard import build_leaderboard, build_sound_leaderboard
from skelcore.compare.profiles import load_profiles
from skelcore.compare.report import write_report

PROFILES = load_profiles()


def _row(shape: str, method: str, d_b: float, defects: str = "", condition: str = "normal", status: str = "ok") -> dict:
    row = {"shape": shape, "method": method, "condition": condition, "seed": 0, "status": status,
           "defects": defects, "d_B": d_b, "n_warnings": float(bool(defects))}
    row.update({f"profile_{p.name}": "n/a" for p in PROFILES})
    return row


def _rows() -> list[dict]:
    """A and B on cases s0-s3; B has a defect on s1, A has failed on s3; C is broken everywhere."""
    return [_row("s0", "A", 0.10), _row("s0", "B", 0.20), _row("s0", "C", 0.01, "collapse"),
            _row("s1", "A", 0.30), _row("s1", "B", 0.05, "incomplete"), _row("s1", "C", 0.01, "collapse"),
            _row("s2", "A", 0.50), _row("s2", "B", 0.30), _row("s2", "C", 0.02, "outside"),
            _row("s3", "A", math.nan, status="failed"), _row("s3", "B", 0.10), _row("s3", "C", 0.02, "collapse")]


def test_it_keeps_the_cases_where_every_method_is_sound_and_ranks_their_plain_means():
    rows = _rows()
    full = build_leaderboard(rows, PROFILES, ["A", "B", "C"], ["normal"])
    # the full board ranks only A (B and C have a defect somewhere), on means over different cases
    assert [(e.method, e.rank["d_B"]) for e in full.entries] == [("A", 1), ("B", None), ("C", None)]
    board = build_sound_leaderboard(rows, PROFILES, ["A", "B", "C"], ["normal"])
    assert board.sound_cases == {"normal": (2, 4)}  # s0 and s2 (s1: B's defect; s3: A failed)
    assert board.never_sound == {"normal": ["C"]}
    by = {e.method: e for e in board.entries}
    assert set(by) == {"A", "B"}
    assert by["A"].mean["d_B"] == np.mean([0.10, 0.50]) and by["B"].mean["d_B"] == np.mean([0.20, 0.30])
    assert (by["A"].rank["d_B"], by["B"].rank["d_B"]) == (2, 1)
    assert by["A"].n_sound == by["A"].n_jobs == 2 and not any(by["A"].tainted.values())
    text = board.to_markdown()
    assert "normal: 2 of 4 cases (shape, seed) where every method is sound; left out, sound on no case: C" in text
    assert "(1)" in text


def test_no_common_sound_case_is_said_so_and_each_condition_is_apart():
    rows = _rows() + [_row("s0", "A", 0.1, condition="noisy"), _row("s0", "B", 0.1, "outside", condition="noisy"),
                      _row("s1", "A", 0.1, "outside", condition="noisy"), _row("s1", "B", 0.1, condition="noisy")]
    board = build_sound_leaderboard(rows, PROFILES, ["A", "B", "C"], ["normal", "noisy"])
    assert board.sound_cases == {"normal": (2, 4), "noisy": (0, 2)}
    assert {e.condition for e in board.entries} == {"normal"}
    only_noisy = build_sound_leaderboard([r for r in rows if r["condition"] == "noisy"], PROFILES, ["A", "B"], ["noisy"])
    assert only_noisy.entries == [] and "No case where every method is sound." in only_noisy.to_markdown()


def test_it_is_written_beside_the_leaderboard_and_shown_in_the_report(tmp_path):
    rows = _rows()
    board = build_leaderboard(rows, PROFILES, ["A", "B", "C"], ["normal"])
    board.sound = build_sound_leaderboard(rows, PROFILES, ["A", "B", "C"], ["normal"])
    paths = board.write(tmp_path)
    assert {p.rsplit("/", 1)[1] for p in paths.values()} == {
        "leaderboard.md", "leaderboard.csv", "leaderboard.tex",
        "leaderboard_sound.md", "leaderboard_sound.csv", "leaderboard_sound.tex"}
    sound_csv = (tmp_path / "leaderboard_sound.csv").read_text().splitlines()
    assert [line.split(",")[0] for line in sound_csv[1:]] == ["A", "B"]
    page = write_report(tmp_path, [], board, Store(tmp_path), shapes=[], methods=["A", "B", "C"], conditions=["normal"])
    text = open(page, encoding="utf-8").read()
    assert "Leaderboard over the cases where every method is sound" in text
    assert "2 of 4 cases" in text and text.count("<table class=lb>") >= 2
