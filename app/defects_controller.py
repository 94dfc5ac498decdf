"""Wires the defects (those of the skeleton, and a scan's openings and stray points) into the main
window through its public interface (:class:`skelscope.window_api.WindowApi`): the Defects dock lists the shown
evaluation's defects (:func:`skelscope.scene.defects.defect_rows`), the 3-D overlay draws them
(:class:`skelscope.view.defect_overlay.DefectOverlay`), View > Show defects (Shift+D) shows or hides them;
selecting a row frames the camera on its bounding box and highlights it, and a click on the curve
highlights the clicked branch (whose length, radius, metric means and flags the pick panel shows).
A row's context menu, and a button under the table for the selected row, offer its edits (``row_actions``, set by the window to the edit controller's:
"Prune this branch", "Delete this edge", "Cut this cycle").
"""

from __future__ import annotations

from typing import Any, Callable

from PySide6 import QtCore, QtWidgets

from .panels.defects import DefectsPanel
from .scene import SceneEvent
from .scene.defects import DefectRow, branch_edges, branch_points, defect_rows, sound_line
from .view.defect_overlay import DefectOverlay
from .window_api import RIGHT, ActionSpec, WindowApi

__all__ = ["DefectsController"]


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
        self._shown_ev: Any = None
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
        window.element_picked.connect(self._picked)
        self.scene.subscribe(self._on_scene)
        self.refresh()

    def _on_scene(self, event: SceneEvent) -> None:
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
        """The panel and the overlay from the scene's evaluation."""
        ev = self.scene.evaluation
        self._shown_ev = ev
        self.selected = None
        self.rows = defect_rows(ev)
        self.fix_button.setVisible(False)
        self.panel.show_rows(None if ev is None else self.rows, "" if ev is None else sound_line(ev))
        self.overlay.show(ev, self.rows, self._cloud_size(), stale=bool(self.scene.stale))
        self.overlay.set_visible(self.visible)

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

    def _row_menu(self, pos: QtCore.QPoint) -> None:
        table = self.panel.table
        index = table.indexAt(pos).row()
        entries = self.actions_of(index)
        if not entries:
            return
        menu = QtWidgets.QMenu(table)
        for text, run in entries:
            menu.addAction(text).triggered.connect(lambda _c=False, r=run: r())
        menu.exec(table.viewport().mapToGlobal(pos))

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
