"""Opening a ``skelcore compare`` run's report rows in the A/B view, from their stored results.

File > "Open comparison run…" (or dropping the run's folder or its ``index.json`` on the window) opens
a dialog listing the run's datasets, conditions, seeds and, for the chosen ones, each method's row of
the report (status and scores); pick method A and method B and "Open A/B view" shows both stored
Evaluations side by side (:class:`skelscope.compare_view.CompareWindow`); "Show A (B) in the main window"
puts that stored result in the 3-D view, where picking shows each element's support. Nothing is
recomputed: :mod:`skelcore.compare.finished_run` reads the jobs' records. Bad input is one
dialog line; big rows are read in a thread.
"""

from __future__ import annotations

import os
import threading
from typing import Any

from PySide6 import QtCore, QtGui, QtWidgets

from skelcore.io.json_numbers import json_float
from skelcore.scores import COLUMN, column_keys, format_score, paired_columns

from .window_api import ActionSpec, WindowApi

__all__ = ["CompareRunDialog", "RunBrowser", "load_ab", "ab_context"]

#: (header, column key or the (skeletal, curve) pair shown as "s/c") of the run browser's table
_SCORE_COLUMNS = [(COLUMN[k].label, k) for k in column_keys(group="paper", compared=True) if COLUMN[k].kind is None] + [
    (f"{sk.short[:-2]} s/c", (sk.key, cv.key)) for _m, sk, cv in paired_columns("paper")]


def _cell(scores: dict[str, Any], key: Any) -> str:
    """A stored job's score(s) with the column's digits, "—" where missing."""
    def one(k: str) -> str:
        return format_score(json_float(scores.get(k)), COLUMN[k].digits, nan="—", missing="—")

    return one(key) if isinstance(key, str) else "/".join(one(k) for k in key)


def load_ab(run: Any, shape: str | None, method_a: str, method_b: str, condition: str | None = None,
            seed: int | None = None) -> tuple[Any, Any, Any, Any]:
    """(job A, job B, Evaluation A, Evaluation B) of two methods for one dataset, condition and seed of
    ``run`` (a :class:`CompareRun`; None picks its first); SkelInputError (one line) on an unknown name
    or a job without stored results."""
    job_a = run.find(shape, method_a, condition, seed)
    job_b = run.find(job_a.shape, method_b, job_a.condition, job_a.seed)
    return job_a, job_b, run.evaluation(job_a), run.evaluation(job_b)


def ab_context(run: Any, job: Any) -> str:
    return f"{job.shape}, {job.condition}, seed {job.seed} — run {run.name}"


BACKGROUND_BYTES = 8_000_000
"""Stored arrays to read above which the dialog reads them in a thread (a 30k-point job's are ~3 MB)."""


class CompareRunDialog(QtWidgets.QDialog):
    """Dataset / condition / seed, the report's rows for them, methods A and B, and the buttons."""

    loaded = QtCore.Signal(int, object, object)  # request token, (jobs, what next), Evaluations or the exception

    def __init__(self, window: WindowApi, run: Any) -> None:
        super().__init__(window.widget)
        self.window, self.run = window, run
        self.view: Any = None  # the last A/B window opened
        self.background_bytes = BACKGROUND_BYTES
        self.busy = False
        self._token = 0
        self.loaded.connect(self._loaded)
        self.setWindowTitle(f"Comparison run: {run.name}")
        self.setModal(False)
        form = QtWidgets.QFormLayout()
        where = QtWidgets.QLabel(str(run.root))
        where.setTextInteractionFlags(QtCore.Qt.TextInteractionFlag.TextSelectableByMouse)
        form.addRow("Run", where)
        self.dataset, self.condition, self.seed = QtWidgets.QComboBox(), QtWidgets.QComboBox(), QtWidgets.QComboBox()
        self.method_a, self.method_b = QtWidgets.QComboBox(), QtWidgets.QComboBox()
        self.dataset.addItems(run.shapes)
        self.condition.addItems(run.conditions)
        form.addRow("Dataset", self.dataset)
        form.addRow("Condition", self.condition)
        form.addRow("Seed", self.seed)
        form.addRow("Method A", self.method_a)
        form.addRow("Method B", self.method_b)
        self.table = QtWidgets.QTableWidget(0, 3 + len(_SCORE_COLUMNS), self)
        self.table.setHorizontalHeaderLabels(["", "method", "status", *(c for c, _ in _SCORE_COLUMNS)])
        self.table.verticalHeader().setVisible(False)
        self.table.setEditTriggers(QtWidgets.QAbstractItemView.EditTrigger.NoEditTriggers)
        self.table.setSelectionBehavior(QtWidgets.QAbstractItemView.SelectionBehavior.SelectRows)
        self.table.setToolTip("the report's rows for this dataset and condition (s/c: skeletal points / curve); "
                              "double-click a row to make it B")
        self.table.cellDoubleClicked.connect(
            lambda row, _col: self.method_b.setCurrentText(self.table.item(row, 1).text()))
        self.open_button = QtWidgets.QPushButton("Open A/B view")
        self.open_button.setDefault(True)
        self.open_button.clicked.connect(self.open_ab)
        self.show_a_button = QtWidgets.QPushButton("Show A in the main window")
        self.show_a_button.setToolTip("A's stored result in the 3-D view: pick an element to see its support")
        self.show_a_button.clicked.connect(self.show_a)
        self.show_b_button = QtWidgets.QPushButton("Show B in the main window")
        self.show_b_button.clicked.connect(self.show_b)
        self.status = QtWidgets.QLabel("")
        self.status.setWordWrap(True)
        buttons = QtWidgets.QHBoxLayout()
        buttons.addWidget(self.open_button)
        buttons.addWidget(self.show_a_button)
        buttons.addWidget(self.show_b_button)
        buttons.addStretch(1)
        layout = QtWidgets.QVBoxLayout(self)
        layout.addLayout(form)
        layout.addWidget(self.table, 1)
        layout.addWidget(self.status)
        layout.addLayout(buttons)
        for box in (self.dataset, self.condition):
            box.currentIndexChanged.connect(self._refill)
        self.seed.currentIndexChanged.connect(self._fill_rows)
        for box in (self.method_a, self.method_b):
            box.currentIndexChanged.connect(self._check)
        self.resize(820, 460)
        self._refill()

    # ---- choices ------------------------------------------------------------------------------
    def select(self, dataset: str | None = None, condition: str | None = None, a: str | None = None,
               b: str | None = None, seed: int | None = None) -> None:
        for box, value in ((self.dataset, dataset), (self.condition, condition)):
            if value is not None:
                box.setCurrentText(value)
        if seed is not None:
            self.seed.setCurrentText(str(seed))
        for box, value in ((self.method_a, a), (self.method_b, b)):
            if value is not None:
                box.setCurrentText(value)

    def choice(self) -> tuple[str, str, int | None, str, str]:
        seed = self.seed.currentText()
        return (self.dataset.currentText(), self.condition.currentText(), int(seed) if seed else None,
                self.method_a.currentText(), self.method_b.currentText())

    def _refill(self) -> None:
        shape, cond = self.dataset.currentText(), self.condition.currentText()
        self.seed.blockSignals(True)
        self.seed.clear()
        self.seed.addItems([str(s) for s in self.run.seeds(shape, cond)])
        self.seed.blockSignals(False)
        methods = self.run.methods_for(shape, cond)
        for i, box in enumerate((self.method_a, self.method_b)):
            keep = box.currentText()
            box.blockSignals(True)
            box.clear()
            box.addItems(methods)
            if keep in methods:
                box.setCurrentText(keep)
            elif len(methods) > i:
                box.setCurrentIndex(i)
            box.blockSignals(False)
        self._fill_rows()

    def _fill_rows(self) -> None:
        shape, cond, seed, _a, _b = self.choice()
        methods = self.run.methods_for(shape, cond, seed)
        self.table.setRowCount(len(methods))
        for r, method in enumerate(methods):
            job = self.run.find(shape, method, cond, seed)
            status, error = self.run.status(job)
            scores = self.run.scores(job) if status == "ok" else {}
            cells = ["", method, status if status == "ok" else f"{status}: {error}"]
            cells += [_cell(scores, key) for _, key in _SCORE_COLUMNS]
            for c, text in enumerate(cells):
                item = QtWidgets.QTableWidgetItem(text)
                if status != "ok":
                    item.setForeground(QtGui.QBrush(QtGui.QColor("#a00000")))
                self.table.setItem(r, c, item)
        self.table.resizeColumnsToContents()
        self._check()

    def _check(self) -> None:
        _shape, _cond, _seed, a, b = self.choice()
        for r in range(self.table.rowCount()):  # which rows are A and B
            method = self.table.item(r, 1)
            role = "/".join(x for x, m in (("A", a), ("B", b)) if method is not None and method.text() == m)
            item = self.table.item(r, 0)
            if item is not None:
                item.setText(role)
                font = item.font()
                font.setBold(True)
                item.setFont(font)
        ok = bool(a and b)
        self.open_button.setEnabled(ok)
        self.show_a_button.setEnabled(bool(a))
        self.show_b_button.setEnabled(bool(b))
        self.status.setText("" if ok else "this dataset and condition have no method to compare")
        if ok and a == b:
            self.status.setText("A and B are the same method")

    # ---- actions ------------------------------------------------------------------------------
    def open_ab(self) -> Any:
        """The A/B view of the chosen rows (returned when read at once; a big run's arrive later)."""
        shape, cond, _seed, a, b = self.choice()

        def show(jobs: list[Any], evs: list[Any]) -> Any:
            self.view = self.window.compare.open(evs[0], evs[1], (a, b), thresholds=None,
                                                 context=ab_context(self.run, jobs[0]))
            self.status.setText(f"opened A: {a} | B: {b} ({shape}, {cond})")
            return self.view

        return self._load([a, b], show)

    def show_a(self) -> Any:
        return self.show_in_window("A")

    def show_b(self) -> Any:
        return self.show_in_window("B")

    def show_in_window(self, which: str) -> Any:
        """Method A's (or B's) stored result in the main window's 3-D view, as if just evaluated."""
        shape, cond, _seed, a, b = self.choice()
        method = a if which == "A" else b

        def show(_jobs: list[Any], evs: list[Any]) -> bool:
            ev = evs[0]
            skeletal = None if ev.skeletal is None else ev.skeletal.points
            curve = None if ev.curve is None else ev.curve.curve
            self.window.open_variant(ev.cloud, skeletal, curve, ev)
            self.status.setText(f"the main window shows {which}: {method} ({shape}, {cond})")
            return True

        return self._load([method], show)

    def _load(self, methods: list[str], then: Any) -> Any:
        """Read the chosen rows' stored Evaluations and call ``then(jobs, evaluations)``: at once when
        their arrays are small (its result is returned), else in a thread (None is returned, the newest
        request wins, the window stays free). A failure is one dialog line."""
        from skelcore.errors import SkelInputError

        shape, cond, seed, _a, _b = self.choice()
        self._token += 1
        try:
            jobs = [self.run.find(shape, m, cond, seed) for m in methods]
            size = sum(self.run.arrays_size(j) for j in jobs)
            if size < self.background_bytes:
                return then(jobs, [self.run.evaluation(j) for j in jobs])
        except SkelInputError as exc:
            self.window.show_error("Comparison run", str(exc))
            return None
        token = self._token
        self.busy = True
        for button in (self.open_button, self.show_a_button, self.show_b_button):
            button.setEnabled(False)
        self.status.setText(f"reading {size / 1e6:.0f} MB of stored results…")

        def work() -> None:
            try:
                out: Any = [self.run.evaluation(j) for j in jobs]
            except Exception as exc:  # noqa: BLE001 - shown as a dialog line, never a crash
                out = exc
            self.loaded.emit(token, (jobs, then), out)

        threading.Thread(target=work, name="skelscope-run-read", daemon=True).start()
        return None

    def _loaded(self, token: int, what: Any, out: Any) -> None:
        if token != self._token:
            return  # a newer request replaced this one
        self.busy = False
        self._check()
        jobs, then = what
        if isinstance(out, Exception):
            from skelcore.errors import SkelInputError

            self.window.show_error("Comparison run", str(out) if isinstance(out, SkelInputError)
                                   else f"{type(out).__name__}: {out}")
            return
        then(jobs, out)


class RunBrowser(QtCore.QObject):
    """File > Open comparison run…, and drops of a run's folder or ``index.json`` on the window."""

    def __init__(self, window: WindowApi) -> None:
        super().__init__(window.widget)
        self.window = window
        self.dialog: CompareRunDialog | None = None
        window.add_action(ActionSpec("open_compare_run", "Open comparison run (skelcore compare folder)…",
                                     "file.compare", self.choose))
        window.add_drop_handler(self.accepts, self.dropped)  # on the 3-D view and anywhere on the window
        window.closing.connect(self.close_dialog)  # the run's dialog closes with the main window

    def close_dialog(self) -> None:
        if self.dialog is not None:
            self.dialog.close()
            self.dialog = None

    @staticmethod
    def run_path(paths: list[str]) -> str | None:
        """The first of ``paths`` that is a compare run (its folder or its index.json)."""
        from skelcore.compare.finished_run import is_run_path

        return next((p for p in paths if is_run_path(p)), None)

    def accepts(self, paths: list[str]) -> bool:
        return self.run_path(paths) is not None

    def dropped(self, paths: list[str]) -> None:
        path = self.run_path(paths)
        if path:
            QtCore.QTimer.singleShot(0, self, lambda: self.open(path))  # not inside the drop: the dialog may be modal

    def choose(self) -> None:
        folder = QtWidgets.QFileDialog.getExistingDirectory(self.window.widget, "Open a skelcore compare output folder",
                                                            self.window.last_dir())
        if folder:
            self.open(folder)

    def open(self, path: str | os.PathLike) -> CompareRunDialog | None:
        """The dialog for the run at ``path`` (a folder or its index.json); a one-line dialog if it is not one."""
        from skelcore.errors import SkelInputError
        from skelcore.compare.finished_run import open_run

        try:
            run = open_run(path)
        except SkelInputError as exc:
            self.window.show_error("Comparison run", str(exc))
            return None
        if self.dialog is not None:
            self.dialog.close()
        self.dialog = CompareRunDialog(self.window, run)
        self.dialog.show()
        return self.dialog
