"""An edit scored in two phases (skelscope.edit_scoring): the four metrics first (the curve recoloured,
the Summary's scores), then the curve's coverage and defects. Meanwhile the Defects dock shows no rows
and says "defects updating…", keeps every mark, and no undo step or A/B view takes the partial
evaluation; a further edit, an undo or a cancel stops a stale second phase; what lands at the end equals
a fresh evaluation. The shape: the cylinder with a twig of test_app_editing."""

from __future__ import annotations

import threading

import numpy as np
import pytest

import skelcore
from skelcore.io import load_cloud

from test_app_editing import assert_same_scores, key, loaded, wait_evaluated

pytestmark = [pytest.mark.gui, pytest.mark.window(questions="default")]


@pytest.fixture
def held(monkeypatch):
    """The second phase waits until ``held.set()`` (a cancel still stops it): a test sees the first
    phase on screen for as long as it needs."""
    import skelscope.session as session
    from skelscope import edit_scoring

    gate = threading.Event()

    def defects_job(partial, start=None):
        real = edit_scoring.defects_job(partial, start)

        def job(progress, cancel):
            while not gate.wait(0.01) and not cancel():
                pass
            return real(progress, cancel)

        return job

    monkeypatch.setattr(session, "defects_job", defects_job)
    yield gate
    gate.set()


def prune_tip_to_second_phase(qtbot, w, tip: int) -> None:
    """Edit mode on, the tip vertex selected and deleted, until the edit's second phase runs."""
    from skelscope.edit_scoring import DEFECTS_TASK

    key(qtbot, w, "E")
    w.select_element("curve", "vertices", tip)
    key(qtbot, w, "Delete")
    qtbot.waitUntil(lambda: w.session.runner.current_name == DEFECTS_TASK, timeout=30000)


def test_the_defects_follow_the_scores_and_never_mix_with_them(window, qtbot, tmp_path, held):
    from skelscope.edit_scoring import UPDATING

    w = window
    cloud_path, _curve, tip = loaded(qtbot, w, tmp_path)
    j = next(k for k, r in enumerate(w.defects.rows) if r.code == "outside")
    w.defects.mark(j, "accepted")
    marks = dict(w.defects.marks)
    landed = []
    w.session.evaluated.connect(landed.append)
    prune_tip_to_second_phase(qtbot, w, tip)
    partial = w.scene.evaluation
    edited = w.scene.curve.curve
    fresh = skelcore.evaluate(load_cloud(cloud_path), curve=edited)
    shown = w.scene.scores()
    for name in ("boundedness_curve", "centeredness_curve", "smoothness_curve"):  # phase one: the four metrics
        assert abs(getattr(shown, name) - getattr(fresh.scores(), name)) <= 1e-12
    np.testing.assert_array_equal(partial.curve.sample_boundedness, fresh.curve.sample_boundedness)
    assert w.defects.rows == [] and w.defects.panel.pending == UPDATING and w.defects.panel.status.text() == UPDATING
    assert w.defects.marks == marks  # kept: the rows they belong to are not known yet
    assert w.edits.evaluation_of(edited) is None and landed == []
    # the Summary follows the recoloured frame (main_window: the panels after the frame)
    qtbot.waitUntil(lambda: "updating" in w.summary.details_text(), timeout=5000)
    held.set()
    wait_evaluated(qtbot, w)
    assert landed == [w.scene.evaluation] and not w.defects.panel.pending
    assert_same_scores(w.scene.scores(), fresh.scores())
    assert w.edits.evaluation_of(edited) is w.scene.evaluation


def test_a_further_edit_an_undo_or_a_cancel_stops_a_stale_second_phase(window, qtbot, tmp_path, held):
    from skelscope.edit_scoring import DEFECTS_TASK

    w = window
    cloud_path, _curve, tip = loaded(qtbot, w, tmp_path)
    first = w.scene.evaluation
    landed = []
    w.session.evaluated.connect(landed.append)
    prune_tip_to_second_phase(qtbot, w, tip)
    pruned = w.scene.curve.curve
    w.edits.select("edge", tuple(int(v) for v in pruned.edges[0]))  # the cylinder's first edge
    key(qtbot, w, "Delete")
    qtbot.waitUntil(lambda: w.session.runner.current_name == DEFECTS_TASK, timeout=30000)
    assert landed == []  # the prune's second phase was dropped, never shown
    assert w.edits.stack.command(1).ev_before is None  # the prune's partial evaluation is kept by no step
    held.set()
    wait_evaluated(qtbot, w)
    assert len(landed) == 1
    fresh = skelcore.evaluate(load_cloud(cloud_path), curve=w.scene.curve.curve)
    assert_same_scores(w.scene.scores(), fresh.scores())

    held.clear()
    key(qtbot, w, "Ctrl+Z")  # back to the prune: its evaluation was never whole, so scored again
    qtbot.waitUntil(lambda: w.session.runner.current_name == DEFECTS_TASK, timeout=30000)
    w.session.runner.cancel()  # Esc during the second phase
    qtbot.waitUntil(lambda: not w.session.runner.running, timeout=30000)
    assert w.defects.panel.pending.startswith("defects not updated") and w.defects.rows == []
    key(qtbot, w, "Ctrl+Z")  # the loaded curve: its whole evaluation, kept by the first step
    assert w.edits.last_scoring == "known" and w.scene.evaluation is first
    assert not w.defects.panel.pending and w.defects.rows


def test_held_frames_wait_for_the_release_or_the_hold_s_end(window, qtbot):
    """An edit holds the view's frames until its scores land (FRAME_HOLD_S at most): one frame shows
    the edited curve coloured; a hold that nothing releases ends by itself."""
    w = window
    qtbot.waitUntil(lambda: not w.view.render_pending, timeout=10000)
    w.view.hold_frames(30.0)
    w.view.request_render()
    qtbot.wait(150)
    assert w.view.render_pending  # held
    w.view.release_frames()
    qtbot.waitUntil(lambda: not w.view.render_pending, timeout=10000)
    w.view.hold_frames(0.2)
    w.view.request_render()
    qtbot.waitUntil(lambda: not w.view.render_pending, timeout=10000)  # the hold ran out


def test_after_esc_stops_the_defects_the_waiting_ab_view_opens_at_once_with_what_is_there(
        window, qtbot, tmp_path, held):
    """The A/B view asked for during the second phase waits for it; Esc stops it and the view opens
    at once: B's four metrics shown, its defect counts and sound line "not computed" (never 0 or
    "sound"), A's whole, B - A of the defects not coloured."""
    from PySide6 import QtCore, QtGui

    w = window
    _cloud_path, _curve, tip = loaded(qtbot, w, tmp_path)
    prune_tip_to_second_phase(qtbot, w, tip)
    partial = w.scene.evaluation
    assert w.edit_compare.open() and w.compare.views == []  # waits for the defects
    key(qtbot, w, "Escape")
    qtbot.waitUntil(lambda: len(w.compare.views) == 1, timeout=5000)
    assert not w.session.runner.running and not w.edit_compare._waiting
    view = w.compare.views[-1]
    assert view.ev_b is partial and view.pending == (False, True)
    assert view.ev_a.curve.curve is w.edits.original
    shown = w.scene.scores()  # the first phase's four metrics, in B's column
    boundedness = next(r for r, (label, *_v) in enumerate(view.rows) if label.startswith("boundedness")
                       and abs(view.rows[r][2] - shown.boundedness_curve) <= 1e-12)
    assert view.cell(boundedness, 2) not in ("—", "not computed")
    assert view.defect_rows, "A's defects listed"
    for r in range(len(view.rows), len(view.rows) + len(view.defect_rows)):
        assert view.cell(r, 2) == "not computed" and view.cell(r, 3) == "—"
        colour = view.table.item(r, 3).foreground().color()
        assert colour not in (QtGui.QColor(QtCore.Qt.GlobalColor.darkGreen), QtGui.QColor(QtCore.Qt.GlobalColor.darkRed))
    last = len(view.rows) + len(view.defect_rows)
    assert view.cell(last, 2) == "not computed" and view.cell(last, 1).startswith("not sound")
