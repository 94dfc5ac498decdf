"""Editing the curve skeleton through the window: edit mode, a pick selects the spurious twig's branch,
Delete prunes it and the window scores the edited curve again (``Evaluation.update`` in the worker),
equal to a fresh evaluation; Ctrl+Z and Ctrl+Shift+Z; a Defects row's "Prune this branch"; File > Save
skeleton as… with its edit log, and never over the loaded file without asking.

The shape: a cylinder's axis (21 vertices, radius 0.5) with a two-edge twig from its middle out to 1.4
units sideways: one spurious branch, partly outside."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest
from PySide6 import QtCore, QtGui

import skelcore
import skelcore.edit as edit
from skelcore import shapes
from skelcore.curve import CurveSkeleton
from skelcore.io import load_cloud, load_curve
from skelcore.io.writers import write_curve, write_point_set

pytestmark = [pytest.mark.gui, pytest.mark.window(questions="default")]

METRICS = ("boundedness_curve", "centeredness_curve", "smoothness_curve", "coverage_curve", "spurious_branches",
           "outside_length_share", "n_boundedness_curve")


def twig_files(tmp_path):
    s = shapes.cylinder(n=3000, seed=2)
    axis = s.curve_vertices
    mid = len(axis) // 2
    v = np.vstack([axis, [[0.7, 0, axis[mid, 2]], [1.4, 0, axis[mid, 2]]]])
    n = len(v)
    e = np.vstack([s.curve_edges, [[mid, n - 2], [n - 2, n - 1]]])
    cloud, curve = str(tmp_path / "cyl.ply"), str(tmp_path / "cyl_curve.ply")
    write_point_set(cloud, s.cloud)
    write_curve(curve, CurveSkeleton.from_raw(v, e))
    return cloud, curve, n - 1  # the twig's end vertex


def scores_of(sc):
    return np.array([np.nan if getattr(sc, k) is None else float(getattr(sc, k)) for k in METRICS])


def assert_same_scores(a, b):
    np.testing.assert_allclose(scores_of(a), scores_of(b), rtol=0, atol=1e-12)


def wait_evaluated(qtbot, w):
    qtbot.waitUntil(lambda: w.scene.evaluation is not None and not w.session.runner.running, timeout=30000)


def loaded(qtbot, w, tmp_path):
    cloud, curve, tip = twig_files(tmp_path)
    assert w.session.load_roles({"cloud": cloud, "curve": curve}) == []
    w.session.start_evaluation()
    wait_evaluated(qtbot, w)
    return cloud, curve, tip


def key(qtbot, w, sequence):
    """A shortcut as the user types it: the window's action for it triggered."""
    seq = QtGui.QKeySequence(sequence)
    (action,) = [a for a in w.actions_by_name.values() if a.shortcut() == seq]
    assert action.isEnabled(), sequence
    action.trigger()


def test_prune_the_picked_twig_then_undo_redo_and_save(window, qtbot, tmp_path):
    w = window
    cloud_path, curve_path, tip = loaded(qtbot, w, tmp_path)
    before = w.scene.scores()
    n_before = w.scene.curve.curve.n_vertices
    assert before.spurious_branches == 1

    key(qtbot, w, "E")
    assert w.edits.active and w.docks["History"].isVisible()
    info = w.select_element("curve", "vertices", tip)  # the pick API: as a click on the twig's end
    assert w.edits.selection == {"kind": "branch", "index": int(info["branch"]["branch"])}
    key(qtbot, w, "Delete")
    assert w.scene.curve.curve.n_vertices < n_before and w.scene.curve.edited
    assert "(edited)" in w.windowTitle()
    assert w.edits.last_scoring == "update"  # Evaluation.update of the shown evaluation, in the worker
    wait_evaluated(qtbot, w)
    after = w.scene.scores()
    edited = w.scene.curve.curve
    fresh = skelcore.evaluate(load_cloud(cloud_path), curve=edited).scores()
    assert after.spurious_branches == 0 and after.boundedness_curve != before.boundedness_curve
    assert_same_scores(after, fresh)
    assert w.edits.history.model().rowCount() == 2  # "loaded curve" and the prune

    key(qtbot, w, "Ctrl+Z")
    assert w.scene.curve.curve.n_vertices == n_before
    assert w.edits.last_scoring == "known"  # the evaluation kept by the undo step: at once
    wait_evaluated(qtbot, w)
    assert_same_scores(w.scene.scores(), before)
    assert "(edited)" not in w.windowTitle()  # every edit undone: the loaded curve again
    key(qtbot, w, "Ctrl+Shift+Z")
    wait_evaluated(qtbot, w)
    assert w.scene.curve.curve.n_vertices == edited.n_vertices
    assert_same_scores(w.scene.scores(), fresh)

    # Save skeleton as: the curve and its edit log; the file evaluates to the window's scores
    out = str(tmp_path / "cyl_pruned.ply")
    assert w.edits.save(out) == [out, str(tmp_path / "cyl_pruned.edits.json")]
    assert_same_scores(skelcore.evaluate(load_cloud(cloud_path), curve=load_curve(out)).scores(), w.scene.scores())
    from skelcore.cli import main as skelcore_cli

    report = tmp_path / "pruned.json"
    assert skelcore_cli(["evaluate", cloud_path, "--curve", out, "--json", str(report)]) == 0  # `skelcore evaluate`
    doc = json.loads(report.read_text())
    shown = w.scene.scores()
    for metric in ("boundedness", "centeredness", "smoothness"):
        assert abs(doc[metric]["curve"] - getattr(shown, f"{metric}_curve")) <= 1e-12
    replayed, changes = edit.replay(load_curve(curve_path), edit.read_log(str(tmp_path / "cyl_pruned.edits.json")))
    assert [c.op for c in changes] == ["prune_branch"] and replayed.n_vertices == edited.n_vertices

    # over the loaded file: asked first; the default keeps the file
    stamp = os.path.getmtime(curve_path), open(curve_path, "rb").read()
    assert w.edits.save(curve_path) == []
    assert w.questions and "loaded curve skeleton" in w.questions[-1][0]
    assert open(curve_path, "rb").read() == stamp[1]
    w.session.ask = lambda question, options: options[1]  # "Replace"
    assert w.edits.save(curve_path)[0] == curve_path
    assert load_curve(curve_path).n_vertices == edited.n_vertices


def test_a_defects_row_prunes_its_branch_and_an_edit_during_an_evaluation_drops_it(window, qtbot, tmp_path):
    w = window
    _cloud, _curve, _tip = loaded(qtbot, w, tmp_path)
    rows = w.defects.rows
    i = next(k for k, r in enumerate(rows) if r.code == "spurious_branches")
    assert [t for t, _ in w.defects.actions_of(i)] == ["Prune this branch"]
    j = next(k for k, r in enumerate(rows) if r.code == "outside")
    assert w.defects.actions_of(j)[0][0].startswith("Delete th")
    n = w.scene.curve.curve.n_vertices

    w.defects.select(i)
    assert w.defects.fix_button.isVisible() and w.defects.fix_button.text() == "Prune this branch"
    w.session.start_evaluation()  # running: the edit drops it, its result never lands
    assert w.session.runner.running
    w.defects.panel.select_row(i)
    w.defects.fix_button.click()
    assert w.scene.curve.curve.n_vertices < n
    wait_evaluated(qtbot, w)
    assert w.scene.evaluation.curve.curve is w.scene.curve.curve or \
        edit.content_hash(w.scene.evaluation.curve.curve) == edit.content_hash(w.scene.curve.curve)
    assert w.scene.scores().spurious_branches == 0
    w.edits.undo()
    assert w.scene.curve.curve.n_vertices == n


def test_join_two_picked_vertices_then_cut_the_cycle_while_the_join_is_scored(window, qtbot, tmp_path):
    w = window
    _cloud, _curve, tip = loaded(qtbot, w, tmp_path)
    w.edits.set_active(True)
    n_edges = w.scene.curve.curve.n_edges
    w.select_element("curve", "vertices", tip)
    w.select_element("curve", "vertices", 12)
    assert w.edits.join_picked()
    assert w.scene.curve.curve.n_edges == n_edges + 1
    assert w.session.runner.running  # scoring the joined curve: the next edit drops it
    w.edits.select("edge", (12, tip))
    assert w.edits.cut_selected_cycle()
    assert w.scene.curve.curve.n_edges == n_edges
    assert w.edits.stack.count() == 2
    wait_evaluated(qtbot, w)
    assert_same_scores(w.scene.scores(), skelcore.evaluate(w.scene.evaluation.cloud, curve=w.scene.curve.curve).scores())


def test_a_session_keeps_the_curve_edits(window, qtbot, tmp_path):
    w = window
    _cloud, curve_path, tip = loaded(qtbot, w, tmp_path)
    w.edits.set_active(True)
    w.select_element("curve", "vertices", tip)
    assert w.edits.delete_selected()
    edited = w.scene.curve.curve
    session = w.saved_sessions.save(str(tmp_path / "edited_session.json"))
    w.session.close_all()
    assert w.edits.stack.count() == 0
    assert w.saved_sessions.open(session) == []
    assert w.scene.curve.path == curve_path and w.scene.curve.edited
    assert edit.content_hash(w.scene.curve.curve) == edit.content_hash(edited)
    assert w.edits.stack.count() == 1
    w.edits.undo()
    assert w.scene.curve.curve.n_vertices == load_curve(curve_path).n_vertices


def test_ctrl_drag_moves_a_curve_vertex(window, qtbot, tmp_path):
    from PySide6.QtTest import QTest

    w = window
    _cloud, _curve, tip = loaded(qtbot, w, tmp_path)
    w.view.image()  # a frame at the final size: the camera is set
    w.edits.set_active(True)
    widget = w.view.plotter
    ratio = widget.devicePixelRatioF()
    old = w.scene.curve.curve.vertices[tip].copy()
    target = np.array([0.2, 0.0, old[2]])  # back towards the axis

    def qt_point(xyz):
        x, y = w.view.world_to_display(xyz)
        return QtCore.QPoint(round(x / ratio), round(widget.height() - y / ratio))

    ctrl = QtCore.Qt.KeyboardModifier.ControlModifier
    QTest.mousePress(widget, QtCore.Qt.MouseButton.LeftButton, ctrl, qt_point(old))
    assert w.edits.dragging == tip
    QTest.mouseRelease(widget, QtCore.Qt.MouseButton.LeftButton, ctrl, qt_point(target))
    assert w.edits.dragging is None and w.edits.stack.count() == 1
    moved = w.scene.curve.curve.vertices[tip]
    x0, y0 = w.view.world_to_display(target)
    x1, y1 = w.view.world_to_display(moved)
    assert abs(x1 - x0) <= 2 * ratio and abs(y1 - y0) <= 2 * ratio  # drawn where it was dropped
    assert np.linalg.norm(moved - old) > 0.5
    wait_evaluated(qtbot, w)
    assert_same_scores(w.scene.scores(), skelcore.evaluate(w.scene.evaluation.cloud, curve=w.scene.curve.curve).scores())


def _ab_values(rows):
    return np.array([[a, b] for _label, a, b, _d in rows], dtype=float)


def test_the_ab_view_opens_the_loaded_curve_against_the_edited_one(window, qtbot, tmp_path):
    """Edit > Compare the loaded curve with the edited one: A the curve as loaded, B the edited one,
    both scored; the table equals fresh evaluations of both. At once when an undo step kept A's
    evaluation; else A is scored in the worker, after the edited curve's own scoring has landed."""
    from skelscope.compare_view import ab_rows

    w = window
    cloud_path, curve_path, tip = loaded(qtbot, w, tmp_path)
    action = w.actions_by_name["compare_edited"]
    assert not action.isEnabled() and not w.edit_compare.button.isEnabled()  # no edit yet
    original = w.scene.curve.curve
    w.edits.set_active(True)
    w.select_element("curve", "vertices", tip)
    key(qtbot, w, "Delete")
    wait_evaluated(qtbot, w)
    assert action.isEnabled() and w.edit_compare.button.isEnabled()
    w.edit_compare.button.click()  # the History dock's button: A's evaluation kept by the undo step
    assert len(w.compare.views) == 1
    view = w.compare.views[-1]
    assert view.ev_a.curve.curve is original and view.ev_b is w.scene.evaluation
    assert view.names == ("cyl_curve.ply as loaded", "cyl_curve.ply edited (1 edit)")
    cloud = load_cloud(cloud_path)
    th = (w.scene.beta_star, w.scene.c_star)
    fresh_a = skelcore.evaluate(cloud, curve=original)
    fresh_b = skelcore.evaluate(cloud, curve=w.scene.curve.curve)
    want = _ab_values(ab_rows(fresh_a.scores(*th), fresh_b.scores(*th)))
    np.testing.assert_allclose(_ab_values(view.rows), want, rtol=0, atol=1e-12)
    spur = next(r for r, (label, *_v) in enumerate(view.rows + view.defect_rows)
                if label == "defects: spurious_branches")
    assert view.cell(spur, 1) == "1" and view.cell(spur, 2) == "0"

    # a saved session's edits (replayed: no evaluation of the loaded curve kept): asked while the
    # edited curve is scored, the view waits for it, then scores A in the worker
    session = w.saved_sessions.save(str(tmp_path / "edited_session.json"))
    w.compare.close_views()
    w.session.close_all()
    w.session.auto_evaluate = True
    assert w.saved_sessions.open(session) == []
    assert w.session.runner.running and w.edits.stack.command(0).ev_before is None
    action.trigger()
    assert w.compare.views == []
    qtbot.waitUntil(lambda: len(w.compare.views) == 1, timeout=60000)
    view = w.compare.views[-1]
    assert view.ev_b is w.scene.evaluation and view.ev_a is not fresh_a
    np.testing.assert_allclose(_ab_values(view.rows), want, rtol=0, atol=1e-12)


@pytest.mark.window(dialogs="record")
def test_an_edit_that_would_leave_nothing_is_refused_and_undo_stops_at_the_start(window, qtbot, tmp_path):
    """Pruning the only branch, or deleting the middle vertex of a two-edge curve, would leave no curve:
    one dialog line, nothing changes; Undo is disabled with nothing to undo (Ctrl+Z then does nothing)."""
    s = shapes.cylinder(n=3000, seed=2)
    cloud, curve_path = str(tmp_path / "cyl.ply"), str(tmp_path / "stub.ply")
    write_point_set(cloud, s.cloud)
    write_curve(curve_path, CurveSkeleton.from_raw(s.curve_vertices[[9, 10, 11]], np.array([[0, 1], [1, 2]])))
    w = window
    assert w.session.load_roles({"cloud": cloud, "curve": curve_path}) == []
    w.session.start_evaluation()
    wait_evaluated(qtbot, w)
    undo, redo = w.actions_by_name["undo"], w.actions_by_name["redo"]
    assert not undo.isEnabled() and not redo.isEnabled()  # nothing to undo at the start
    shown = w.scene.curve.curve
    key(qtbot, w, "E")
    w.select_element("curve", "vertices", 0)  # an end: selects the one branch
    assert w.edits.selection["kind"] == "branch"
    key(qtbot, w, "Delete")
    assert w.dialogs[-1] == "this edit would leave the curve without vertices"
    w.edits.select("vertex", 1)
    assert not w.edits.delete_selected()
    assert w.dialogs[-1] == "this edit would leave the curve without edges" and len(w.dialogs) == 2
    assert w.scene.curve.curve is shown and not w.scene.curve.edited and w.edits.stack.count() == 0
    assert not undo.isEnabled() and not w.session.runner.running and w.scene.evaluation is not None

    w.edits.select("edge", (1, 2))  # one edit, undone: the start again, Undo disabled
    key(qtbot, w, "Delete")
    assert undo.isEnabled()
    key(qtbot, w, "Ctrl+Z")
    assert not undo.isEnabled() and redo.isEnabled() and w.scene.curve.curve is shown
    w.edits.undo()  # past the start (a script's call): nothing happens
    assert w.scene.curve.curve is shown and w.edits.stack.index() == 0 and not w.scene.curve.edited


def test_an_edit_while_the_loaded_curve_is_scored_for_the_ab_view_cancels_that_view(window, qtbot, tmp_path):
    """The A/B view's scoring of the loaded curve runs in the worker: an edit meanwhile cancels it (the
    view never opens with a B no longer shown) and the edited curve is scored as after any edit."""
    w = window
    _cloud, _curve, tip = loaded(qtbot, w, tmp_path)
    w.edits.set_active(True)
    w.select_element("curve", "vertices", tip)
    assert w.edits.delete_selected()
    wait_evaluated(qtbot, w)
    w.edits.stack.command(0).ev_before = None  # no evaluation of the loaded curve kept: A in the worker
    assert w.edit_compare.open() and w.session.runner.current_name == w.edit_compare.NAME
    w.edits.select("edge", (0, 1))
    assert w.edits.delete_selected()  # the A/B scoring cancelled, the edited curve scored instead
    assert w.session.runner.current_name == "evaluation"
    wait_evaluated(qtbot, w)
    qtbot.wait(200)
    assert w.compare.views == []
    assert_same_scores(w.scene.scores(), skelcore.evaluate(w.scene.evaluation.cloud, curve=w.scene.curve.curve).scores())


def test_a_broken_curves_row_joins_its_piece_to_the_rest(window, qtbot, tmp_path):
    """The ``disconnected`` row's fix: an edge from the piece's vertex nearest the rest of the curve to
    that vertex of the rest; scored again, the curve is one piece and the warning is gone."""
    from pathlib import Path

    from skelcore.io.writers import write_curve

    samples = Path(__file__).resolve().parents[2] / "resources" / "samples"
    curve = skelcore.load_curve(samples / "yshape_curve.ply")
    e = np.sort(np.asarray(curve.edges), axis=1)
    broken = CurveSkeleton.from_raw(curve.vertices, np.asarray(curve.edges)[~(e == [3, 4]).all(axis=1)])
    path = str(tmp_path / "broken_curve.ply")
    write_curve(path, broken)
    w = window
    assert w.session.load_roles({"cloud": str(samples / "yshape_cloud.ply"), "curve": path}) == []
    w.session.start_evaluation()
    wait_evaluated(qtbot, w)
    i = next(k for k, r in enumerate(w.defects.rows) if r.code == "disconnected")
    assert [t for t, _ in w.defects.actions_of(i)] == ["Join this piece"]
    w.defects.select(i)
    w.defects.fix_button.click()
    assert w.scene.curve.curve.n_edges == broken.n_edges + 1
    assert {tuple(sorted(x)) for x in np.asarray(w.scene.curve.curve.edges).tolist()} >= {(3, 4)}
    wait_evaluated(qtbot, w)
    assert "disconnected" not in {x.code for x in w.scene.evaluation.warnings}
    assert not any(r.code == "disconnected" for r in w.defects.rows)
