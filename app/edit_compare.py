"""Edit > Compare the loaded curve with the edited one (A/B), also a button under the History list.

Opens the A/B view (:class:`skelscope.compare_view.CompareWindow`, through the window's ``compare``)
with A = the curve skeleton as loaded and B = the edited one, both scored against the same cloud,
skeletal set and settings. B is the shown evaluation (an edit still being scored, or its defects: the view opens
once the whole evaluation lands; Esc stopping the defects opens it at once, B's defects "not computed"); A is the
evaluation an undo step kept of the loaded curve, else the shown one's ``Evaluation.update`` back to the loaded
curve, in the worker (the same as a fresh evaluation).
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, Any, Callable

from PySide6 import QtCore, QtWidgets

from .edit_scoring import DEFECTS_TASK, UPDATE_LOCK
from .window_api import ActionSpec, WindowApi

if TYPE_CHECKING:
    from .edit_controller import EditController

__all__ = ["EditCompare"]

TEXT = "Compare the loaded curve with the edited one (A/B)"


class EditCompare(QtCore.QObject):
    """The action, the History dock's button, and the A/B view they open."""

    NAME = "evaluation of the loaded curve"

    def __init__(self, window: WindowApi, edits: "EditController") -> None:
        super().__init__(window.widget)
        self.window, self.edits = window, edits
        self._pending: Any = None  # B, while A is scored in the worker
        self._waiting = False  # the edited curve still being scored: open once it lands
        self.action = window.add_action(ActionSpec("compare_edited", TEXT, "edit.history", self.open,
                                                   enabled=self.can_open))
        self.button = QtWidgets.QPushButton("Compare with the loaded curve (A/B)", edits.history.parentWidget())
        self.button.setToolTip(TEXT)
        self.button.clicked.connect(self.open)
        edits.history_buttons.addWidget(self.button)
        edits.stack.indexChanged.connect(self._refresh)
        self.button.setEnabled(False)
        window.session.runner.succeeded.connect(self._succeeded)
        window.session.runner.cancelled.connect(self._cancelled)
        window.session.evaluated.connect(self._scored)

    def _refresh(self, _index: int = 0) -> None:
        import shiboken6

        if shiboken6.isValid(self.edits.stack) and shiboken6.isValid(self.button):  # not while the window goes
            self.button.setEnabled(self.can_open())

    def can_open(self) -> bool:
        """The curve has edits (the stack's position is past its start)."""
        return self.edits.original is not None and self.edits.stack.index() > 0 and self.window.scene.curve is not None

    def open(self, partial: bool = False) -> bool:
        """Open the A/B view now, or once the scores it needs are known (True when it will open);
        ``partial``: with B's four metrics alone when its defects were stopped (Esc)."""
        w = self.window
        if not self.can_open():
            w.show_message("no edits: the curve is as loaded")
            return False
        if w.session.runner.current_name in ("evaluation", DEFECTS_TASK):  # B's scores or its defects
            self._waiting = True
            w.show_message("A/B: waiting for the edited curve's scores")
            return True
        ev_b = self.edits.evaluation_of(w.scene.curve.curve, partial=partial)
        if ev_b is None:
            w.show_error("Compare with the loaded curve", "score the edited curve first (Evaluate, F5)")
            return False
        ev_a = self._known_original(ev_b)
        if ev_a is not None:
            self._show(ev_a, ev_b)
            return True
        original = self.edits.original

        def job(progress: Callable[[float, str], None], cancel: Callable[[], bool]) -> Any:
            progress(0.0, "scoring the loaded curve")
            with UPDATE_LOCK:  # one Evaluation.update at a time (they share the evaluation's caches)
                return ev_b.update(original)

        self._pending = ev_b
        w.session.runner.start(job, self.NAME)
        w.show_message("A/B: scoring the loaded curve…")
        return True

    def _known_original(self, ev_b: Any) -> Any:
        """An undo step's evaluation of the loaded curve under B's settings, or None."""
        stack, original = self.edits.stack, self.edits.original
        for i in range(stack.count()):
            cmd = stack.command(i)
            for curve, ev in ((cmd.before, cmd.ev_before), (cmd.after, cmd.ev_after)):
                if curve is original and ev is not None and ev.params == ev_b.params:
                    return ev
        return None

    def _scored(self, _ev: Any) -> None:
        if self._waiting and not self.window.session.runner.running:
            self._waiting = False
            QtCore.QTimer.singleShot(0, self, self.open)

    def _cancelled(self, name: str) -> None:
        """Esc stopped what the view waited for: the defects (the view opens at once with B's four
        metrics, its defects "not computed"), or B's scores (nothing to show: it does not open). Seen
        after the event, when a further edit's scoring, which the view then waits for, has started."""
        if self._waiting:
            QtCore.QTimer.singleShot(0, self, lambda: self._after_cancel(name))

    def _after_cancel(self, name: str) -> None:
        if not self._waiting or self.window.session.runner.current_name in ("evaluation", DEFECTS_TASK):
            return  # opened meanwhile, or still waiting for a further edit's scores
        self._waiting = False
        if name == DEFECTS_TASK:
            self.open(partial=True)
        else:
            self.window.show_message("A/B: the edited curve's scoring was cancelled")

    def _succeeded(self, name: str, result: Any) -> None:
        if name != self.NAME or self._pending is None:
            return
        ev_b, self._pending = self._pending, None
        if self.window.scene.evaluation is not ev_b:  # edited again meanwhile: B is not shown any more
            return
        self._show(result, ev_b)

    def _show(self, ev_a: Any, ev_b: Any) -> Any:
        layer = self.window.scene.curve
        name = os.path.basename(layer.path) if layer is not None and layer.path else "curve"
        n = self.edits.stack.index()
        return self.window.compare.open(ev_a, ev_b, (f"{name} as loaded", f"{name} edited ({n} edit{'s' * (n != 1)})"))
