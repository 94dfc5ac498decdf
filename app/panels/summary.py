"""The summary table in the paper's layout (rows d_B/d_Wp, boundedness, centeredness, smoothness;
columns skeletal points / curve skeleton), each score with the number of elements it counted (SPEC 5),
and the editable thresholds beta*, c* (SPEC 2-3) that re-score without recomputing."""

from __future__ import annotations

import math
from typing import Any

from PySide6 import QtCore, QtGui, QtWidgets

ROWS = ("d_B / d_Wp", "boundedness", "centeredness", "smoothness")
COLUMNS = ("skeletal points", "curve skeleton")


def _num(value: Any, digits: int = 3) -> str:
    if value is None:
        return "—"
    v = float(value)
    return "nan" if math.isnan(v) else f"{v:.{digits}f}"


def summary_cells(summary: dict[str, Any] | None) -> list[list[str]]:
    """The table's text, row by row (Qt-free so it can be tested and reused)."""
    cells = [["—", "—"] for _ in ROWS]
    if summary is None:
        return cells
    topo = summary.get("topology")
    if topo is not None:
        cells[0][0] = f"{_num(topo['bottleneck'], 4)} / {_num(topo['wasserstein'], 4)}"
    for r, metric in enumerate(("boundedness", "centeredness", "smoothness"), start=1):
        for c, kind in enumerate(("skeletal", "curve")):
            value = summary[metric][kind]
            if value is None:
                continue
            n = summary["counts"][metric][kind]
            cells[r][c] = f"{_num(value)}  (n = {n})"
    return cells


NO_RESULT = "No evaluation yet: load a cloud and a skeleton, then Evaluate (F5)."


class SummaryPanel(QtWidgets.QWidget):
    thresholds_changed = QtCore.Signal(float, float)
    rerun_requested = QtCore.Signal()

    def __init__(self, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.table = QtWidgets.QTableWidget(len(ROWS), len(COLUMNS), self)
        self.table.setHorizontalHeaderLabels(list(COLUMNS))
        self.table.setVerticalHeaderLabels(list(ROWS))
        self.table.setEditTriggers(QtWidgets.QAbstractItemView.EditTrigger.NoEditTriggers)
        self.table.horizontalHeader().setSectionResizeMode(QtWidgets.QHeaderView.ResizeMode.Stretch)
        self.table.verticalHeader().setSectionResizeMode(QtWidgets.QHeaderView.ResizeMode.ResizeToContents)
        self.table.setVerticalScrollBarPolicy(QtCore.Qt.ScrollBarPolicy.ScrollBarAlwaysOff)
        self.table.setSizeAdjustPolicy(QtWidgets.QAbstractScrollArea.SizeAdjustPolicy.AdjustToContents)
        self.beta_star = self._spin("bounded means beta > beta* (SPEC 2)")
        self.c_star = self._spin("centred means c > c* (SPEC 3)")
        self.details = QtWidgets.QLabel(NO_RESULT)
        self.details.setWordWrap(True)
        # Shown while the results are out of date (see set_stale).
        self.rerun = QtWidgets.QPushButton("", self)
        self.rerun.setStyleSheet("QPushButton { color: #8a4b00; font-weight: bold; }")
        self.rerun.clicked.connect(self.rerun_requested.emit)
        self.rerun.setVisible(False)
        self.stale = ""
        form = QtWidgets.QFormLayout()
        form.addRow("beta* (boundedness)", self.beta_star)
        form.addRow("c* (centeredness)", self.c_star)
        layout = QtWidgets.QVBoxLayout(self)
        layout.addWidget(self.table)
        layout.addWidget(self.rerun)
        layout.addLayout(form)
        layout.addWidget(self.details)
        layout.addStretch(1)
        self.show_summary(None)

    def _spin(self, tip: str) -> QtWidgets.QDoubleSpinBox:
        spin = QtWidgets.QDoubleSpinBox(self)
        spin.setRange(0.0, 1.0)
        spin.setDecimals(3)
        spin.setSingleStep(0.05)
        spin.setValue(0.75)
        spin.setToolTip(tip)
        spin.setKeyboardTracking(False)
        spin.valueChanged.connect(self._emit_thresholds)
        return spin

    def _emit_thresholds(self, *_: Any) -> None:
        self.thresholds_changed.emit(self.beta_star.value(), self.c_star.value())

    def set_thresholds(self, beta_star: float, c_star: float) -> None:
        """Show thresholds (e.g. from a new evaluation's params) without re-emitting them."""
        for spin, value in ((self.beta_star, beta_star), (self.c_star, c_star)):
            spin.blockSignals(True)
            spin.setValue(float(value))
            spin.blockSignals(False)

    def show_summary(self, summary: dict[str, Any] | None, evaluation: Any = None) -> None:
        for r, row in enumerate(summary_cells(summary)):
            for c, text in enumerate(row):
                item = QtWidgets.QTableWidgetItem(text)
                item.setTextAlignment(QtCore.Qt.AlignmentFlag.AlignCenter)
                self.table.setItem(r, c, item)
        self._grey(bool(self.stale))
        if summary is None or evaluation is None:
            # Nothing shown: no line may describe a run whose values are gone.
            self.details.setText(NO_RESULT)
            return
        lines = [f"boundedness estimator: {evaluation.params.boundedness_method}"]
        topo = summary.get("topology")
        if topo is not None:
            lines.append(f"eps* = {_num(topo['eps_star'], 4)} (normalized units), K = {topo['n_bars']} bars compared")
        total = evaluation.timings.get("total") if evaluation.timings else None
        if total is not None:
            lines.append(f"evaluated in {total:.2f} s")
        self.details.setText("\n".join(lines))

    def set_stale(self, reason: str) -> None:
        """Mark the results out of date ("settings changed", "inputs changed"): values greyed, a
        re-run button naming the reason; "" clears the mark."""
        self.stale = reason
        self.rerun.setText(f"{reason}: re-run (F5)" if reason else "")
        self.rerun.setVisible(bool(reason))
        self._grey(bool(reason))

    def _grey(self, grey: bool) -> None:
        colour = self.palette().color(QtGui.QPalette.ColorGroup.Disabled, QtGui.QPalette.ColorRole.Text) if grey \
            else self.palette().color(QtGui.QPalette.ColorRole.Text)
        for r in range(self.table.rowCount()):
            for c in range(self.table.columnCount()):
                item = self.table.item(r, c)
                if item is not None:
                    item.setForeground(colour)
        self.details.setEnabled(not grey)

    def is_greyed(self) -> bool:
        item = self.table.item(1, 0)
        return item is not None and item.foreground().color() != self.palette().color(QtGui.QPalette.ColorRole.Text)

    def cell_text(self, row: str, column: str) -> str:
        item = self.table.item(ROWS.index(row), COLUMNS.index(column))
        return "" if item is None else item.text()
