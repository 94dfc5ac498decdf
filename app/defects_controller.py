"""Wires the defects (those of the skeleton, and a scan's openings and stray points) into the main
window through its public interface (:class:`skelscope.window_api.WindowApi`): the Defects dock lists the shown
evaluation's defects (:func:`skelscope.scene.defects.defect_rows`), the 3-D overlay draws them
(:class:`skelscope.view.defect_overlay.DefectOverlay`), View > Show defects (Shift+D) shows or hides them;
selecting a row frames the camera on its bounding box and highlights it, and a click on the curve
highlights the clicked branch (whose length, radius, metric means and flags the pick panel shows).
A row's context menu, and a button under the table for the selected row, offer its edits (``row_actions``, set by the window to the edit controller's:
"Prune this branch", "Delete this edge", "Cut this cycle").
Evaluate > Next defect (N) and Previous defect (Shift+N) walk the rows, wrapping around; a row's context
menu marks it "fixed", "accepted" or "ignored" (:data:`MARKS`), shown in the table's mark column and kept
by :func:`mark_key` across evaluations, in saved sessions and in the saved edit log ("defect_marks").
Marks belong to the skeleton they were made for (:meth:`DefectsController.skeleton_key`: the cloud,
skeletal set and curve as loaded; an edit keeps the skeleton): another skeleton or cloud starts
unmarked, and reopening one brings its marks back.
"""

from __future__ import annotations

import os
from typing import Any, Callable

from PySide6 import QtCore, QtWidgets

from .edit_scoring import DEFECTS_TASK, UPDATING, defects_pending
from .panels.defects import DefectsPanel
from .scene import SceneEvent
from .scene.defects import DefectRow, branch_edges, branch_points, defect_rows, sound_line
from .view.defect_overlay import DefectOverlay
from .window_api import RIGHT, ActionSpec, WindowApi

__all__ = ["DefectsController", "MARKS", "mark_key", "row_keys"]

MARKS = ("fixed", "accepted", "ignored")


def mark_key(code: str, title: str, nth: int) -> str:
    """A defect's key for its mark: its code, its title and its index among the rows of that code."""
    return f"{code}|{title}|{nth}"


def row_keys(rows: list[DefectRow]) -> list[str]:
    """Each row's :func:`mark_key`, in order."""
    seen: dict[str, int] = {}
    keys = []
    for row in rows:
        nth = seen.get(row.code, 0)
        seen[row.code] = nth + 1
        keys.append(mark_key(row.code, row.title, nth))
    return keys


class DefectsController(QtCore.QObject):
    def __init__(self, window: WindowApi) -> None:
        super().__init__(window.widget)
        self.window = window
        self.scene = window.scene
        self.view = window.view
        self.panel = DefectsPanel(window.widget)
        self.overlay = DefectOverlay(self.view)
        self.rows: list[DefectRow] = []
        self.visible = True
        self.selected: DefectRow | None = None  # the highlighted defect or clicked branch
        #: mark_key -> one of MARKS; kept while a new evaluation still has the key
        self.marks: dict[str, str] = {}
        self.keys: list[str] = []
        self._shown_ev: Any = None
        #: ``is_edit() -> bool``: the layer change under way is an edit of the shown curve (the window
        #: sets it to the edit controller's), which keeps the skeleton and so its marks
        self.is_edit: Callable[[], bool] = lambda: False
        self._ids: dict[str, str] = {}  # role -> the identity of its layer as loaded (skeleton_key)
        self._serial = 0  # numbers data loaded without a file (each one another skeleton)
        self._skeleton: tuple[str, ...] = self.skeleton_key()
        self._kept: dict[tuple[str, ...], dict[str, str]] = {}  # the marks of skeletons shown before
        dock = window.add_dock("Defects", self.panel, RIGHT)
        main = window.widget
        main.tabifyDockWidget(window.docks["Barcodes"], dock)
        window.docks["Barcodes"].raise_()
        self.panel.selected.connect(self.select)
        #: ``row_actions(row) -> [(text, run)]``: the edits a row offers in its context menu
        self.row_actions: Callable[[DefectRow], list[tuple[str, Callable[[], Any]]]] = lambda row: []
        table = self.panel.table
        table.setContextMenuPolicy(QtCore.Qt.ContextMenuPolicy.CustomContextMenu)
        table.customContextMenuRequested.connect(self._row_menu)
        #: the selected row's edit as a button under the table (hidden when the row offers none)
        self.fix_button = QtWidgets.QPushButton("", self.panel)
        self.fix_button.setVisible(False)
        self.fix_button.clicked.connect(self._fix_selected)
        self.panel.layout().addWidget(self.fix_button)
        self.panel.show_toggled.connect(self.set_visible)
        self.action = window.add_action(ActionSpec("show_defects", "Show defects", "view.style", self.set_visible, "Shift+D",
                                     checked=lambda: self.visible))
        window.add_action(ActionSpec("next_defect", "Next defect", "evaluate.colour", lambda: self.step(1), "N",
                                     enabled=lambda: bool(self.rows)))
        window.add_action(ActionSpec("previous_defect", "Previous defect", "evaluate.colour", lambda: self.step(-1),
                                     "Shift+N", enabled=lambda: bool(self.rows)))
        window.element_picked.connect(self._picked)
        self.scene.subscribe(self._on_scene)
        for signal in (window.session.runner.finished, window.session.runner.cancelled):
            signal.connect(self._task_ended)
        self.refresh()

    def _task_ended(self, _name: str) -> None:
        """An edit's second phase cancelled: the dock says so (its line follows the worker)."""
        if self.panel.pending and self.panel.pending != self.pending_line(self.scene.evaluation):
            self.refresh()

    def skeleton_key(self) -> tuple[str, ...]:
        """The skeleton shown, as its marks know it: per role (cloud, skeletal, curve), its file, or a
        number for data loaded without one; "" for no layer."""
        return tuple(self._ids.get(role, "") for role in ("cloud", "skeletal", "curve"))

    def _layer_changed(self, role: str) -> None:
        """A layer loaded, replaced or closed: unless an edit, the marks go with the skeleton they were
        made for (kept aside) and the new skeleton's come back (none if never marked)."""
        layer = self.scene.layers.get(role)
        if role == "curve" and layer is not None and self.is_edit():
            return
        if layer is None:
            self._ids.pop(role, None)
        elif layer.path:
            self._ids[role] = os.path.abspath(layer.path)
        else:
            self._serial += 1
            self._ids[role] = f"#{self._serial}"
        key = self.skeleton_key()
        if key == self._skeleton:
            return
        if self.marks:
            self._kept[self._skeleton] = dict(self.marks)
        else:
            self._kept.pop(self._skeleton, None)
        self._skeleton = key
        self.marks = dict(self._kept.get(key, {}))
        self.panel.set_marks(self._row_marks())

    def _on_scene(self, event: SceneEvent) -> None:
        if event.kind == "layer" and event.layer in ("cloud", "skeletal", "curve"):
            self._layer_changed(event.layer)
        # a result set again (even the same one) clears the picks and marks: the highlight goes too
        if event.kind == "quantities" or (event.kind == "layer" and self.scene.evaluation is not self._shown_ev):
            self.refresh()
        elif event.kind == "stale" and self.scene.evaluation is not None:
            # out-of-date results: their defects greyed like their colours, the selection kept
            self.overlay.show(self.scene.evaluation, self.rows, self._cloud_size(), stale=bool(self.scene.stale))
            if self.selected is not None:
                self.overlay.select(self.scene.evaluation, self.selected, self._cloud_size())
            self.overlay.set_visible(self.visible)

    def refresh(self) -> None:
        """The panel and the overlay from the scene's evaluation; an edit's first phase (its defects
        still updating, :mod:`skelscope.edit_scoring`) shows no rows and keeps every mark."""
        ev = self.scene.evaluation
        self._shown_ev = ev
        self.selected = None
        pending = self.pending_line(ev)
        self.rows = [] if pending else defect_rows(ev)
        self.keys = row_keys(self.rows)
        if ev is not None and not pending:  # a new evaluation keeps the marks whose defect it still has
            self.marks = {k: v for k, v in self.marks.items() if k in self.keys}
        self.fix_button.setVisible(False)
        self.panel.show_rows(None if ev is None else self.rows, "" if ev is None or pending else sound_line(ev),
                             self._row_marks(), pending)
        self.overlay.show(ev, self.rows, self._cloud_size(), stale=bool(self.scene.stale))
        self.overlay.set_visible(self.visible)

    def pending_line(self, ev: Any) -> str:
        """What the dock says of an edit's first phase: its defects updating, or not updated (the second
        phase cancelled); "" for a whole evaluation."""
        if not defects_pending(ev):
            return ""
        if self.window.session.runner.current_name in (DEFECTS_TASK, "evaluation"):
            return UPDATING
        return "defects not updated (cancelled): Evaluate (F5) finds them"

    def _row_marks(self) -> list[str]:
        return [self.marks.get(k, "") for k in self.keys]

    def step(self, by: int) -> int:
        """Select and frame the row ``by`` rows after the selected one (wrapping; from none: the first
        or the last). Returns its index (-1: no rows)."""
        if not self.rows:
            return -1
        current = self.panel.selected_row()
        index = (0 if by > 0 else len(self.rows) - 1) if current < 0 else (current + by) % len(self.rows)
        self.select(index)
        return index

    def mark(self, index: int, mark: str | None) -> None:
        """Mark the ``index``-th row (one of :data:`MARKS`; None or "" clears its mark)."""
        if mark and mark not in MARKS:
            raise ValueError(f"mark must be one of {', '.join(MARKS)}")
        if not 0 <= index < len(self.rows):
            return
        key = self.keys[index]
        if mark:
            self.marks[key] = mark
        else:
            self.marks.pop(key, None)
        self.panel.set_marks(self._row_marks())

    def set_marks(self, marks: dict[str, str]) -> None:
        """Marks as saved (a session) for the skeleton shown: kept whole until the next evaluation,
        which keeps those it has."""
        self.marks = {str(k): str(v) for k, v in marks.items() if v in MARKS}
        if self.scene.evaluation is not None and not self.window.session.runner.running:
            self.marks = {k: v for k, v in self.marks.items() if k in self.keys}
        self.panel.set_marks(self._row_marks())

    def actions_of(self, index: int) -> list[tuple[str, Callable[[], Any]]]:
        """The edits the ``index``-th row offers (its context menu's entries)."""
        return self.row_actions(self.rows[index]) if 0 <= index < len(self.rows) else []

    def run_row_action(self, index: int, text: str) -> Any:
        """Run the ``index``-th row's edit named ``text``, as its context menu would."""
        for name, run in self.actions_of(index):
            if name == text:
                return run()
        raise ValueError(f"row {index} offers no {text!r} (it offers: {[n for n, _ in self.actions_of(index)]})")

    def _fix_selected(self) -> None:
        index = self.panel.selected_row()
        entries = self.actions_of(index)
        if entries:
            entries[0][1]()

    def row_menu(self, index: int) -> QtWidgets.QMenu | None:
        """The ``index``-th row's context menu: its edits, then "Mark fixed / accepted / ignored"
        (checked: its mark; unchecking clears it). None for no row."""
        if not 0 <= index < len(self.rows):
            return None
        menu = QtWidgets.QMenu(self.panel.table)
        for text, run in self.actions_of(index):
            menu.addAction(text).triggered.connect(lambda _c=False, r=run: r())
        if menu.actions():
            menu.addSeparator()
        current = self.marks.get(self.keys[index], "")
        for m in MARKS:
            act = menu.addAction(f"Mark {m}")
            act.setCheckable(True)
            act.setChecked(current == m)
            act.triggered.connect(lambda on, i=index, mk=m: self.mark(i, mk if on else None))
        return menu

    def _row_menu(self, pos: QtCore.QPoint) -> None:
        table = self.panel.table
        menu = self.row_menu(table.indexAt(pos).row())
        if menu is not None:
            menu.exec(table.viewport().mapToGlobal(pos))
            menu.deleteLater()

    def _cloud_size(self) -> float:
        cloud = self.scene.cloud
        return 2.0 if cloud is None else float(cloud.point_size)

    def select(self, index: int) -> None:
        """Select the ``index``-th defect (-1: none): highlighted, and the camera frames it."""
        ev = self.scene.evaluation
        if ev is None or not 0 <= index < len(self.rows):
            self.selected = None
            self.fix_button.setVisible(False)
            self.overlay.select(ev, None)
            return
        row = self.rows[index]
        self.selected = row
        entries = self.actions_of(index)
        self.fix_button.setText(entries[0][0] if entries else "")
        self.fix_button.setVisible(bool(entries))
        if self.panel.selected_row() != index:
            self.panel.blockSignals(True)
            self.panel.select_row(index)
            self.panel.blockSignals(False)
        self.overlay.select(ev, row, self._cloud_size())
        self.overlay.set_visible(self.visible)
        box = row.bounds()
        if box is None:
            self.view.reset_camera()
        else:
            self.view.frame_box(*box)
        self.window.show_message(f"{row.title}: {row.size}", 8000)

    def _picked(self, info: dict[str, Any] | None) -> None:
        """A click on the curve selects its branch: drawn in the pick colour (the pick panel says the rest)."""
        ev = self.scene.evaluation
        branch = None if info is None else info.get("branch")
        if branch is None:
            if self.selected is not None and self.selected.code == "branch":
                self.selected = None
                self.overlay.select(ev, None)
            return
        b = int(branch["branch"])
        self.selected = DefectRow("branch", f"branch #{b}", "", "curve", branches=(b,),
                                  edges=branch_edges(ev, (b,)), points=branch_points(ev, (b,)))
        self.panel.blockSignals(True)
        self.panel.select_row(-1)
        self.panel.blockSignals(False)
        self.overlay.select(ev, self.selected, self._cloud_size())
        self.overlay.set_visible(self.visible)

    def set_visible(self, on: bool) -> None:
        """Show or hide every defect drawn in 3-D (View > Show defects, the panel's box)."""
        self.visible = bool(on)
        if self.panel.show_box.isChecked() != self.visible:
            self.panel.show_box.blockSignals(True)
            self.panel.show_box.setChecked(self.visible)
            self.panel.show_box.blockSignals(False)
        self.overlay.set_visible(self.visible)
        if self.action.isChecked() != self.visible:
            self.action.blockSignals(True)
            self.action.setChecked(self.visible)
            self.action.blockSignals(False)
