"""Walking the defects: Evaluate > Next defect (N) and Previous defect (Shift+N) select and frame the
Defects dock's rows in turn, wrapping around; a row's context menu marks it fixed, accepted or ignored
(the table's mark column, the status line counts the unmarked ones); the marks are saved in sessions
and in the saved edit log under "defect_marks", and a new evaluation keeps those it still has.

The skeleton: the cut cylinder with a spur of tests/app/test_app_defects.py (three defects)."""

from __future__ import annotations

import json

import pytest
from PySide6 import QtGui

from skelcore.io import write_curve_ply, write_points_ply
from test_app_defects import spurred_cut_cylinder

pytestmark = [pytest.mark.gui, pytest.mark.window(size=(1100, 750), auto_evaluate=True, dialogs="record")]


def _key(w, sequence):
    """A shortcut as the user types it: the one window action for it, enabled, triggered."""
    seq = QtGui.QKeySequence(sequence)
    (action,) = [a for a in w.actions_by_name.values() if a.shortcut() == seq]
    assert action.isEnabled(), sequence
    action.trigger()


def _wait_evaluated(w, qtbot):
    qtbot.waitUntil(lambda: w.scene.evaluation is not None and not w.session.runner.running
                    and len(w.defects.rows) > 0, timeout=60000)


def test_n_walks_the_defects_and_marks_survive_a_saved_session(window, qtbot, tmp_path):
    from skelscope.defects_controller import mark_key

    s, curve, _spur = spurred_cut_cylinder()
    cloud, curve_path = str(tmp_path / "cut_cloud.ply"), str(tmp_path / "cut_curve.ply")
    write_points_ply(cloud, s.cloud)
    write_curve_ply(curve_path, curve.vertices, curve.edges)
    w = window
    w.session.load_files([cloud, curve_path])
    _wait_evaluated(w, qtbot)
    d, panel = w.defects, w.defects.panel
    n = len(d.rows)
    assert n >= 2 and panel.selected_row() == -1
    assert w.actions_by_name["next_defect"].shortcut().toString() == "N"
    assert w.actions_by_name["previous_defect"].shortcut().toString() == "Shift+N"

    # N: the first row, then the next; the last one wraps to the first, Shift+N back to the last
    _key(w, "N")
    assert panel.selected_row() == 0 and d.selected is d.rows[0]
    _key(w, "N")
    assert panel.selected_row() == 1 and d.selected is d.rows[1]
    for _ in range(n - 1):
        _key(w, "N")
    assert panel.selected_row() == 0  # wrapped
    _key(w, "Shift+N")
    assert panel.selected_row() == n - 1 and d.selected is d.rows[n - 1]

    # mark the spur accepted: its mark column, one fewer unmarked
    assert f"{n} found, {n} unmarked" in panel.status.text()
    spur = next(i for i, r in enumerate(d.rows) if r.code == "spurious_branches")
    menu = d.row_menu(spur)
    entries = {a.text(): a for a in menu.actions() if a.text()}
    assert {"Prune this branch", "Mark fixed", "Mark accepted", "Mark ignored"} <= set(entries)
    entries["Mark accepted"].trigger()
    key = mark_key("spurious_branches", d.rows[spur].title, 0)
    assert d.marks == {key: "accepted"}
    assert panel.table.item(spur, 2).text() == "accepted"
    assert f"{n} found, {n - 1} unmarked" in panel.status.text()

    # a new evaluation of the same skeleton keeps it
    w.session.start_evaluation()
    qtbot.waitUntil(lambda: not w.session.runner.running, timeout=60000)
    _wait_evaluated(w, qtbot)
    assert d.marks == {key: "accepted"} and panel.table.item(spur, 2).text() == "accepted"

    # saved in the session, and back after closing everything and opening it
    path = str(tmp_path / "cut_session.json")
    w.saved_sessions.save(path)
    assert json.loads(open(path).read())["defect_marks"] == {key: "accepted"}
    w.session.close_all()
    d.set_marks({})
    assert d.marks == {}
    assert w.saved_sessions.open(path) == []
    _wait_evaluated(w, qtbot)
    assert d.marks == {key: "accepted"}
    assert panel.table.item(spur, 2).text() == "accepted"
    assert f"{n - 1} unmarked" in panel.status.text()
    assert d.row_menu(spur) is not None and [a.isChecked() for a in d.row_menu(spur).actions()
                                             if a.text().startswith("Mark ")] == [False, True, False]

    # the missing part ignored, then an edit that removes the spur (its outside edges deleted): the new
    # evaluation keeps the mark whose defect is still there and drops the spur's
    from jsonschema import ValidationError

    from skelcore.edit import read_log
    from skelcore.io.schemas import validator

    missing = next(i for i, r in enumerate(d.rows) if r.code == "incomplete")
    d.mark(missing, "ignored")
    missing_key = d.keys[missing]
    outside = next(i for i, r in enumerate(d.rows) if r.code == "outside")
    d.run_row_action(outside, d.actions_of(outside)[0][0])
    qtbot.waitUntil(lambda: "spurious_branches" not in [r.code for r in d.rows] and not w.session.runner.running,
                    timeout=60000)
    assert d.marks == {missing_key: "ignored"}
    assert f"{len(d.rows)} found, {len(d.rows) - 1} unmarked" in panel.status.text()

    # the skeleton saved with its edit log: the log carries the marks
    out = str(tmp_path / "cut_edited.ply")
    written = w.edits.save(out)
    assert written[1].endswith("cut_edited.edits.json")
    log = read_log(written[1])
    assert log["defect_marks"] == {missing_key: "ignored"} and log["operations"]
    validator("edit_log").validate(log)  # its JSON Schema allows the key
    with pytest.raises(ValidationError):
        validator("edit_log").validate({**log, "defect_marks": {missing_key: "done"}})


@pytest.mark.window(size=(1100, 750), auto_evaluate=True, dialogs="record", questions="default")
def test_marks_belong_to_the_skeleton_they_were_made_for(window, qtbot, tmp_path):
    """Another curve or another cloud opened: no mark of the skeleton before shows; that skeleton
    reopened (or its saved session opened) brings them back; an edit keeps them."""
    from skelcore.curve import CurveSkeleton

    s, curve, _spur = spurred_cut_cylinder()
    cloud, curve_a = str(tmp_path / "cut_cloud.ply"), str(tmp_path / "cut_curve.ply")
    curve_b, cloud_b = str(tmp_path / "cut_curve_b.ply"), str(tmp_path / "cut_cloud_b.ply")
    write_points_ply(cloud, s.cloud)
    write_curve_ply(curve_a, curve.vertices, curve.edges)
    axis = CurveSkeleton.from_raw(s.curve_vertices, s.curve_edges)  # the whole axis: another skeleton
    write_curve_ply(curve_b, axis.vertices, axis.edges)
    write_points_ply(cloud_b, s.cloud[::2])
    w, d = window, window.defects
    w.session.load_files([cloud, curve_a])
    _wait_evaluated(w, qtbot)
    spur = next(i for i, r in enumerate(d.rows) if r.code == "spurious_branches")
    d.mark(spur, "accepted")
    marked = dict(d.marks)
    session = w.saved_sessions.save(str(tmp_path / "a_session.json"))

    assert w.session.load_as("curve", curve_b)  # another curve skeleton of the same cloud
    assert d.marks == {}  # at once, not only once its evaluation has landed
    qtbot.waitUntil(lambda: w.scene.evaluation is not None and not w.session.runner.running, timeout=60000)
    assert d.marks == {} and "accepted" not in [d.panel.table.item(r, 2).text() for r in range(len(d.rows))]
    assert w.session.load_as("curve", curve_a)  # the first one again: its marks are back
    _wait_evaluated(w, qtbot)
    assert d.marks == marked and d.panel.table.item(spur, 2).text() == "accepted"

    assert w.session.load_as("cloud", cloud_b)  # another cloud (the question's default clears the curve)
    assert d.marks == {}
    assert w.saved_sessions.open(session) == []  # the session carries them
    _wait_evaluated(w, qtbot)
    assert d.marks == marked and d.panel.table.item(spur, 2).text() == "accepted"

    w.edits.set_active(True)  # an edit keeps the skeleton, so its marks
    d.mark(next(i for i, r in enumerate(d.rows) if r.code == "incomplete"), "ignored")
    w.edits.select("vertex", int(curve.n_vertices - 1))
    assert w.edits.delete_selected()
    qtbot.waitUntil(lambda: not w.session.runner.running, timeout=60000)
    assert "ignored" in d.marks.values()
