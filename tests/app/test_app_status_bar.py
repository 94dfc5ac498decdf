"""The status bar's message beside a running task's widgets (stage, progress, Cancel) on a small
screen: 1366 x 768 at QT_SCALE_FACTOR 1.5 gives a 911 x 512 window. The message is drawn whole, or
elided with "…" and whole in the tooltip, and never under the stage label (docs/guide/viewer.md
"Sessions and small screens")."""

from __future__ import annotations

import pytest
from PySide6 import QtWidgets

from test_app_edit_phases import held, prune_tip_to_second_phase  # noqa: F401 (a fixture)
from test_app_editing import loaded

pytestmark = [pytest.mark.gui, pytest.mark.window(questions="default", size=(911, 512))]

#: the messages a running task can stand beside (app/session.py, app/edit_compare.py)
WHILE_RUNNING = ["evaluating…", "scoring the edited curve…", "skeletonizing…",
                 "A/B: scoring the loaded curve…", "A/B: waiting for the edited curve's scores"]


def assert_readable(w) -> str:
    """The message as drawn fits left of the first task widget; whole, or elided with its tooltip."""
    bar = w.statusBar()
    QtWidgets.QApplication.processEvents()
    full = bar.currentMessage()
    shown = bar.shown_message() if hasattr(bar, "shown_message") else full  # Qt's own bar: clipped, not elided
    left = 6  # Qt's message margin
    right = left + bar.fontMetrics().horizontalAdvance(shown)
    assert w.stage.isVisible()
    assert right <= w.stage.x() - 2, f"{shown!r} ends at {right} px, the stage label starts at {w.stage.x()}"
    if shown != full:
        assert shown.endswith("…") and full.startswith(shown[:-1]) and bar.toolTip() == full
    else:
        assert bar.toolTip() == ""
    stage = w.stage.toolTip() or w.stage.text()
    assert w.stage.text() == stage or (w.stage.text().endswith("…") and w.stage.toolTip() == stage)
    return shown


def test_an_edit_s_message_shows_whole_beside_its_second_phase(window, qtbot, tmp_path, held):  # noqa: F811
    """"scores of the edited curve shown; defects updating…" once showed as "…shown; defect" under
    "defects: starting…"."""
    from skelscope.edit_scoring import UPDATING

    w = window
    assert w.width() == 911
    _cloud, _curve, tip = loaded(qtbot, w, tmp_path)
    prune_tip_to_second_phase(qtbot, w, tip)
    qtbot.waitUntil(lambda: w.stage.isVisible() and UPDATING in w.statusBar().currentMessage(), timeout=10000)
    assert assert_readable(w) == f"scores of the edited curve shown; {UPDATING}"
    for text in WHILE_RUNNING:
        w.show_message(text)
        assert assert_readable(w) == text
    long = "Picture: wrote " + ", ".join(f"neuron_754534424_view_{i}.png" for i in range(6))
    w.show_message(long)
    assert assert_readable(w) != long  # elided, whole in the tooltip
    held.set()
    qtbot.waitUntil(lambda: not w.session.runner.running, timeout=30000)
    assert not w.stage.isVisible()
    w.show_message(long)
    QtWidgets.QApplication.processEvents()
    bar = w.statusBar()
    assert bar.message_rect().right() > w.width() - 20  # the whole bar is the message's again


def test_the_status_bar_alone_elides_and_gives_its_tooltip(qtbot):
    from skelscope.status_bar import StatusBar

    bar = StatusBar()
    qtbot.addWidget(bar)
    label = QtWidgets.QLabel("stage")
    label.setFixedWidth(200)
    bar.addPermanentWidget(label)
    bar.resize(400, 30)
    bar.show()
    qtbot.waitExposed(bar)
    text = "a message far longer than the two hundred pixels the label leaves it, by some way"
    bar.showMessage(text)
    QtWidgets.QApplication.processEvents()
    assert bar.message_rect().right() < label.x()
    assert bar.shown_message().endswith("…") and bar.toolTip() == text and bar.currentMessage() == text
    label.hide()
    bar.resize(2000, 30)
    QtWidgets.QApplication.processEvents()
    assert bar.shown_message() == text and bar.toolTip() == ""
    bar.clearMessage()
    assert bar.toolTip() == ""
