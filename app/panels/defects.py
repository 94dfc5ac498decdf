"""The Defects panel: one row per defect of the shown evaluation, with its size in the
engine's words (:func:`skelscope.scene.defects.defect_rows`), the sound / not-sound line, and the switch that
shows or hides the defects in the 3-D view. Selecting a row emits ``selected`` with its index."""

from __future__ import annotations

from PySide6 import QtCore, QtGui, QtWidgets

from skelcore.colors import DEFECT_COLORS

from ..scene.defects import DefectRow

__all__ = ["DefectsPanel", "NO_EVALUATION", "NONE_FOUND"]

NO_EVALUATION = "Run an evaluation to see the skeleton's defects."
NONE_FOUND = "defects: none found"


class DefectsPanel(QtWidgets.QWidget):
    selected = QtCore.Signal(int)  # the row's index, -1 when none is selected
    show_toggled = QtCore.Signal(bool)

    def __init__(self, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.rows: list[DefectRow] = []
        self.status = QtWidgets.QLabel(NO_EVALUATION, self)
        self.status.setWordWrap(True)
        self.show_box = QtWidgets.QCheckBox("show defects in 3D (Shift+D)", self)
        self.show_box.setChecked(True)
        self.show_box.toggled.connect(self.show_toggled)
        self.marks: list[str] = []
        self._sound = ""
        self._shown = False
        self._pending = ""
        self.table = QtWidgets.QTableWidget(0, 3, self)
        self.table.setHorizontalHeaderLabels(["defect", "size", "mark"])
        self.table.verticalHeader().setVisible(False)
        self.table.setEditTriggers(QtWidgets.QAbstractItemView.EditTrigger.NoEditTriggers)
        self.table.setSelectionBehavior(QtWidgets.QAbstractItemView.SelectionBehavior.SelectRows)
        self.table.setSelectionMode(QtWidgets.QAbstractItemView.SelectionMode.SingleSelection)
        self.table.setWordWrap(True)
        self.table.horizontalHeader().setStretchLastSection(True)
        self.table.itemSelectionChanged.connect(self._selection_changed)
        self.table.setMinimumHeight(90)
        layout = QtWidgets.QVBoxLayout(self)
        layout.setContentsMargins(2, 2, 2, 2)
        layout.addWidget(self.status)
        layout.addWidget(self.show_box)
        layout.addWidget(self.table, 1)

    def show_rows(self, rows: list[DefectRow] | None, sound: str = "", marks: list[str] | None = None,
                  pending: str = "") -> None:
        """The rows of an evaluation (None: no evaluation shown), each with its mark ("": none);
        ``pending``: no rows yet, this line instead (an edit's defects still updating)."""
        self._pending = pending
        if pending:
            rows, marks = [], []
        self.table.blockSignals(True)
        self.table.clearSelection()
        self.rows = list(rows or [])
        self.table.setRowCount(len(self.rows))
        for i, row in enumerate(self.rows):
            title = QtWidgets.QTableWidgetItem(row.title)
            colour = DEFECT_COLORS.get(row.code)
            if colour is not None:
                title.setIcon(_swatch(colour))
            title.setToolTip(f"[{row.code}]" + (f" {row.column}" if row.column else ""))
            size = QtWidgets.QTableWidgetItem(row.size)
            size.setToolTip(row.size)
            self.table.setItem(i, 0, title)
            self.table.setItem(i, 1, size)
            self.table.setItem(i, 2, QtWidgets.QTableWidgetItem(""))
        self.table.blockSignals(False)
        self._sound = sound
        self._shown = rows is not None
        self.set_marks(marks or [])

    @property
    def pending(self) -> str:
        """The line shown instead of rows ("" when rows are shown)."""
        return self._pending

    def set_marks(self, marks: list[str]) -> None:
        """Each row's mark ("fixed", "accepted", "ignored" or ""), and the status line's unmarked count."""
        self.marks = list(marks) + [""] * (len(self.rows) - len(marks))
        for i, mark in enumerate(self.marks[:len(self.rows)]):
            item = self.table.item(i, 2)
            if item is not None:
                item.setText(mark)
        self.table.resizeColumnToContents(0)
        self.table.resizeRowsToContents()
        sound = self._sound
        if self._pending:
            self.status.setText(self._pending)
        elif not self._shown:
            self.status.setText(NO_EVALUATION)
        elif not self.rows:
            self.status.setText(f"{NONE_FOUND} ({sound})" if sound else NONE_FOUND)
        else:
            open_ = sum(1 for m in self.marks[:len(self.rows)] if not m)
            found = f"{len(self.rows)} found, {open_} unmarked"
            self.status.setText(f"{found}; {sound}" if sound else found)

    def select_row(self, index: int) -> None:
        """Select a row as a click would (-1 clears)."""
        if index < 0:
            self.table.clearSelection()
        else:
            self.table.selectRow(index)

    def selected_row(self) -> int:
        picked = self.table.selectionModel().selectedRows()
        return picked[0].row() if picked else -1

    def _selection_changed(self) -> None:
        self.selected.emit(self.selected_row())


def _swatch(rgb: tuple[int, int, int]) -> QtGui.QIcon:
    pix = QtGui.QPixmap(12, 12)
    pix.fill(QtGui.QColor(*rgb))
    return QtGui.QIcon(pix)
