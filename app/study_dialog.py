"""The Study dialog: run the paper's degradation study on the loaded cloud and show its table.

The study (skelcore.experiments.study.run_study) runs in the viewer's worker thread (app.worker.TaskRunner:
progress, Cancel honoured at the engine's checkpoints, no stale result). Each row of the table can
be opened in the 3D view through the main window's ``open_variant(cloud, skeletal, curve, evaluation)``:
its stored evaluation is shown at once, nothing is recomputed. The window passes its own parameters
and thresholds (beta*, c*), which the dialog names above its table.
"""

from __future__ import annotations

import os
from typing import Any

from PySide6 import QtCore, QtWidgets

from skelcore.params import Params

from .worker import TaskRunner
from skelcore.scores import LOCAL_METRICS

__all__ = ["StudyDialog"]


class StudyDialog(QtWidgets.QDialog):
    """Settings, Run / Cancel, a progress bar and the results table (cells "skeletal/curve")."""

    def __init__(self, parent: QtWidgets.QWidget | None, cloud_path: str, params: Params | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle(f"Study: {os.path.basename(cloud_path)}")
        self.setModal(False)
        self.cloud_path = str(cloud_path)
        self.params = params if params is not None else Params()
        self.result: Any = None  # skelcore.experiments.study.StudyResult after a run
        self.error: str | None = None
        self._out_dir: str | None = None
        self.runner = TaskRunner(self)
        self.runner.progressed.connect(self._progressed)
        self.runner.succeeded.connect(self._succeeded)
        self.runner.failed.connect(self._failed)
        self.runner.cancelled.connect(self._cancelled)
        self.runner.finished.connect(self._finished)
        self._build()

    # ---- layout -------------------------------------------------------------------------------
    def thresholds_text(self) -> str:
        p = self.params
        return (f"thresholds from the window: beta* = {p.beta_star:g}, c* = {p.c_star:g}; "
                f"boundedness estimator: {p.boundedness_method}")

    def _build(self) -> None:
        form = QtWidgets.QFormLayout()
        self.thresholds = QtWidgets.QLabel(self.thresholds_text())
        self.thresholds.setWordWrap(True)
        form.addRow(self.thresholds)
        self.noise = QtWidgets.QDoubleSpinBox(decimals=3, minimum=0.0, maximum=1.0, singleStep=0.01, value=0.05)
        self.noise.setToolTip("noise ratio of the noise row (paper: 0.05); 0 leaves the row out")
        form.addRow("Noise ratio", self.noise)
        self.noise_model = QtWidgets.QComboBox()
        self.noise_model.addItems(["reference", "isotropic"])
        self.noise_model.setToolTip("reference: sigma = ratio x each coordinate (paper's toolbox); "
                                    "isotropic: ratio x RMS distance to the box centre")
        form.addRow("Noise model", self.noise_model)
        self.sparse_mode = QtWidgets.QComboBox()
        self.sparse_mode.addItems(["random points", "voxel grid"])
        form.addRow("Sparse row", self.sparse_mode)
        self.sparse_n = QtWidgets.QSpinBox(minimum=0, maximum=10**8, value=0)
        self.sparse_n.setSpecialValueText("N / 4")
        self.sparse_n.setToolTip("points kept by random downsampling (0 = a quarter of the cloud)")
        form.addRow("Sparse points", self.sparse_n)
        self.grid = QtWidgets.QDoubleSpinBox(decimals=4, minimum=0.0001, maximum=1e6, singleStep=0.01, value=0.05)
        self.grid.setToolTip("voxel-grid cell in the cloud's units (grid anchored at the box's min corner)")
        form.addRow("Grid cell", self.grid)
        self.base_grid = QtWidgets.QDoubleSpinBox(decimals=4, minimum=0.0, maximum=1e6, singleStep=0.01, value=0.0)
        self.base_grid.setSpecialValueText("off")
        self.base_grid.setToolTip("normal row = voxel-grid average of the cloud with this cell (paper's tree: "
                                  "0.02, with a 0.05 grid for the sparse row)")
        form.addRow("Base grid cell", self.base_grid)
        self.seed = QtWidgets.QSpinBox(minimum=0, maximum=2**31 - 1, value=0)
        form.addRow("Seed", self.seed)
        self.out_dir = QtWidgets.QLineEdit()
        self.out_dir.setPlaceholderText("optional: folder for every variant's files and the tables")
        browse = QtWidgets.QPushButton("…")
        browse.clicked.connect(self._browse)
        row = QtWidgets.QHBoxLayout()
        row.addWidget(self.out_dir)
        row.addWidget(browse)
        form.addRow("Output folder", row)
        self.skeleton_cmd = QtWidgets.QLineEdit()
        self.skeleton_cmd.setPlaceholderText("optional: my_skel {in} {out_skeletal} {out_curve}")
        form.addRow("Skeleton command", self.skeleton_cmd)
        self.sparse_mode.currentIndexChanged.connect(self._mode_changed)
        self._mode_changed()

        self.run_button = QtWidgets.QPushButton("Run")
        self.run_button.clicked.connect(self.start)
        self.cancel_button = QtWidgets.QPushButton("Cancel")
        self.cancel_button.setEnabled(False)
        self.cancel_button.clicked.connect(self.runner.cancel)
        self.progress_bar = QtWidgets.QProgressBar(minimum=0, maximum=1000)
        self.status = QtWidgets.QLabel("")
        buttons = QtWidgets.QHBoxLayout()
        buttons.addWidget(self.run_button)
        buttons.addWidget(self.cancel_button)
        buttons.addWidget(self.progress_bar, 1)

        self.table = QtWidgets.QTableWidget(0, 6)
        self.table.setHorizontalHeaderLabels(["shape", "d_B/d_Wp", *LOCAL_METRICS, ""])
        self.table.setEditTriggers(QtWidgets.QAbstractItemView.EditTrigger.NoEditTriggers)
        self.table.horizontalHeader().setSectionResizeMode(QtWidgets.QHeaderView.ResizeMode.ResizeToContents)
        self.table.verticalHeader().setVisible(False)
        self.table.setToolTip("each cell: skeletal point set / curve skeleton")
        self.open_buttons: list[QtWidgets.QPushButton] = []

        layout = QtWidgets.QVBoxLayout(self)
        layout.addLayout(form)
        layout.addLayout(buttons)
        layout.addWidget(self.status)
        layout.addWidget(self.table, 1)
        self.resize(760, 520)

    def _mode_changed(self) -> None:
        grid = self.sparse_mode.currentIndex() == 1
        self.grid.setEnabled(grid)
        self.sparse_n.setEnabled(not grid)

    def _browse(self) -> None:
        folder = QtWidgets.QFileDialog.getExistingDirectory(self, "Write study files into", os.path.dirname(self.cloud_path))
        if folder:
            self.out_dir.setText(folder)

    # ---- running ------------------------------------------------------------------------------
    def settings(self) -> dict[str, Any]:
        """The run_study keywords the widgets describe."""
        grid = self.sparse_mode.currentIndex() == 1
        return {
            "noise": float(self.noise.value()) or None,
            "noise_model": self.noise_model.currentText(),
            "sparse": None if grid or self.sparse_n.value() == 0 else int(self.sparse_n.value()),
            "grid": float(self.grid.value()) if grid else None,
            "base_grid": float(self.base_grid.value()) or None,
            "seed": int(self.seed.value()),
            "out_dir": self.out_dir.text().strip() or None,
            "skeleton_cmd": self.skeleton_cmd.text().strip() or None,
        }

    def start(self) -> None:
        from skelcore.io import load_cloud
        from skelcore.experiments.study import run_study

        kwargs = self.settings()
        self._out_dir = kwargs["out_dir"]
        path, params = self.cloud_path, self.params
        name = os.path.splitext(os.path.basename(path))[0]

        def job(progress, cancel):
            last = [-1.0]

            def coarse(fraction: float, stage: str) -> None:
                # one signal per visible percent: the stage text changes at every engine stage,
                # which would otherwise emit a signal per stage (PySide6 6.12's emit leaks a
                # reference to True per call, see the report; fewer emits also keep the GUI calm)
                if fraction - last[0] >= 0.01 or fraction >= 1.0:
                    last[0] = fraction
                    progress(fraction, stage)

            cloud = load_cloud(path)
            return run_study(cloud, params=params, name=name, inputs=(path,), progress=coarse, cancel=cancel, **kwargs)

        self.result = None
        self.error = None
        self.table.setRowCount(0)
        self.open_buttons = []
        self.progress_bar.setValue(0)
        self.status.setText("running…")
        self.run_button.setEnabled(False)
        self.cancel_button.setEnabled(True)
        self.runner.start(job, "study")

    def _progressed(self, fraction: float, stage: str) -> None:
        self.progress_bar.setValue(int(round(fraction * 1000)))
        self.status.setText(stage)

    def _succeeded(self, _name: str, result: Any) -> None:
        self.result = result
        self._fill(result)
        total = sum(sum(r.timings.values()) for r in result.rows)
        where = f"; files in {self._out_dir}" if self._out_dir else ""
        p = result.params
        self.status.setText(f"done in {total:.1f} s (beta* = {p.beta_star:g}, c* = {p.c_star:g}, boundedness: "
                            f"{p.boundedness_method}){where}")
        self.progress_bar.setValue(1000)

    def _failed(self, _name: str, exc: object, _tb: str) -> None:
        self.error = str(exc)
        self.status.setText(f"failed: {exc}")

    def _cancelled(self, _name: str) -> None:
        self.status.setText("cancelled")

    def _finished(self, _name: str) -> None:
        self.run_button.setEnabled(True)
        self.cancel_button.setEnabled(False)

    def _fill(self, result: Any) -> None:
        rows = result.table()[1:]
        self.table.setRowCount(len(rows))
        can_open = callable(getattr(self.parent(), "open_variant", None))
        for i, (cells, row) in enumerate(zip(rows, result.rows)):
            for j, text in enumerate(cells):
                item = QtWidgets.QTableWidgetItem(text)
                if j:
                    item.setTextAlignment(QtCore.Qt.AlignmentFlag.AlignCenter)
                self.table.setItem(i, j, item)
            button = QtWidgets.QPushButton("Open in 3D view")
            button.setEnabled(can_open)
            if not can_open:
                button.setToolTip("the main window cannot show variants")
            button.setProperty("study_row", i)
            button.clicked.connect(self._open_clicked)
            self.table.setCellWidget(i, 5, button)
            self.open_buttons.append(button)

    @QtCore.Slot()
    def _open_clicked(self) -> None:
        index = self.sender().property("study_row") if self.sender() is not None else None
        if self.result is not None and index is not None:
            self.open_row(self.result.rows[int(index)])

    def open_row(self, row: Any) -> None:
        opener = getattr(self.parent(), "open_variant", None)
        if callable(opener):
            opener(row.cloud, row.skeletal, row.curve, row.evaluation)

    def closeEvent(self, event: Any) -> None:  # noqa: N802
        self.runner.discard()  # cancelled and detached, not waited for: its result can never land
        super().closeEvent(event)

    def reject(self) -> None:
        self.runner.discard()
        super().reject()
