"""Proofreading from end to end on a real scan (docs/guide/viewer.md "Editing the curve skeleton"):
pc-skeletor's broken hammer opened in the window, its defects walked with N, fixed with the Defects
rows' fixes, the fix undone and redone, the skeleton saved, and ``skelcore evaluate`` of the saved
file giving the scores the window shows.

The broken hammer: tests/broken_hammer.py (the real hammer scan, cao's curve cut to the middle of
its handle and a twig out through its side)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from broken_hammer import broken_hammer_curve
from PySide6 import QtGui

import skelcore.edit as edit
from skelcore.io import load_curve
from skelcore.io.writers import write_curve, write_point_set

pytestmark = [pytest.mark.gui, pytest.mark.window(size=(1100, 750), questions="default")]

SHOWN = (("boundedness", "boundedness_curve"), ("centeredness", "centeredness_curve"),
         ("smoothness", "smoothness_curve"))


def broken_hammer(folder: Path) -> tuple[str, str]:
    cloud, curve = broken_hammer_curve()
    paths = str(folder / "hammer.ply"), str(folder / "hammer_pc_skeletor_curve.ply")
    write_point_set(paths[0], cloud)
    write_curve(paths[1], curve)
    return paths


def _key(w, sequence: str) -> None:
    """A shortcut as the user types it: the one window action for it, enabled, triggered."""
    seq = QtGui.QKeySequence(sequence)
    (action,) = [a for a in w.actions_by_name.values() if a.shortcut() == seq]
    assert action.isEnabled(), sequence
    action.trigger()


def _settled(qtbot, w) -> None:
    """Both phases of the scoring shown (an edit's defects included)."""
    from skelscope.edit_scoring import defects_pending

    qtbot.waitUntil(lambda: w.scene.evaluation is not None and not w.session.runner.running
                    and not defects_pending(w.scene.evaluation), timeout=60000)


def test_the_broken_hammer_walked_fixed_undone_redone_saved_and_scored_alike(window, qtbot, tmp_path):
    w = window
    cloud, curve_path = broken_hammer(tmp_path)
    assert w.session.load_roles({"cloud": cloud, "curve": curve_path}) == []
    w.session.start_evaluation()
    _settled(qtbot, w)
    d = w.defects
    codes = [r.code for r in d.rows]
    assert "spurious_branches" in codes and "outside" in codes and "incomplete" in codes, codes

    # the walk: N selects each row in turn and frames it; a row with a fix shows it on the button
    fixes = {}
    for i in range(len(d.rows)):
        _key(w, "N")
        assert d.panel.selected_row() == i and d.selected is d.rows[i]
        offered = [text for text, _run in d.actions_of(i)]
        assert d.fix_button.isVisible() == bool(offered)
        if offered:
            fixes[d.rows[i].code] = offered[0]
    assert fixes.get("spurious_branches") == "Prune this branch", fixes
    assert "incomplete" not in fixes  # a missing part has no edit that makes it up

    # the spur's fix (the button of its selected row) prunes the twig, which was also the outside part
    broken = w.scene.curve.curve
    spur = codes.index("spurious_branches")
    d.select(spur)
    d.fix_button.click()
    _settled(qtbot, w)
    fixed = w.scene.curve.curve
    assert fixed.n_vertices == broken.n_vertices - 2
    scores = w.scene.scores()
    assert scores.spurious_branches == 0 and scores.outside_length_share == 0.0
    assert [r.code for r in d.rows] == ["incomplete"] * codes.count("incomplete")

    # undo brings the twig and its scores back, redo the fix (each the evaluation its step kept)
    _key(w, "Ctrl+Z")
    _settled(qtbot, w)
    assert edit.content_hash(w.scene.curve.curve) == edit.content_hash(broken)
    assert w.scene.scores().spurious_branches == 1
    _key(w, "Ctrl+Shift+Z")
    _settled(qtbot, w)
    assert edit.content_hash(w.scene.curve.curve) == edit.content_hash(fixed)

    saved = str(tmp_path / "hammer_fixed.ply")
    assert w.edits.save(saved)[0] == saved
    assert edit.content_hash(load_curve(saved)) == edit.content_hash(fixed)
    out = tmp_path / "scores.json"
    run = subprocess.run([sys.executable, "-m", "skelcore", "evaluate", cloud, "--curve", saved, "--json", str(out),
                          "--quiet"], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    report = json.loads(out.read_text())
    shown = w.scene.scores()
    for row, key in SHOWN:  # the Summary's curve column, as printed, and the numbers behind it
        value = report[row]["curve"]
        assert value == pytest.approx(getattr(shown, key), abs=1e-12), key
        assert report["counts"][row]["curve"] == getattr(shown, f"n_{key}"), key
        assert w.summary.cell_text(row, "curve skeleton").startswith(f"{value:.3f}"), row
    diagnostics = report["diagnostics"]
    for value, key in ((report["coverage"]["curve"]["fraction"], "coverage_curve"),
                       (diagnostics["completeness"]["curve"], "completeness_curve"),
                       (diagnostics["spurious_branches"]["spurious"], "spurious_branches"),
                       (diagnostics["outside"]["length_share"], "outside_length_share")):
        assert value == pytest.approx(getattr(shown, key), abs=1e-12), key
