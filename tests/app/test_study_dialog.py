"""The Study dialog: runs in the worker thread, fills the table, opens a row, cancels."""

from __future__ import annotations

import pytest

pytest.importorskip("PySide6")

from PySide6 import QtCore, QtWidgets  # noqa: E402

from skelscope.study_dialog import StudyDialog  # noqa: E402
from skelcore import shapes  # noqa: E402
from skelcore.io import write_points_ply  # noqa: E402

pytestmark = pytest.mark.gui


class _Viewer(QtWidgets.QWidget):
    def __init__(self) -> None:
        super().__init__()
        self.opened: list[tuple] = []

    def open_variant(self, cloud, skeletal, curve, evaluation=None) -> None:
        self.opened.append((cloud, skeletal, curve, evaluation))


@pytest.fixture
def cloud_file(tmp_path):
    path = tmp_path / "cyl.ply"
    write_points_ply(path, shapes.cylinder(900, seed=9).cloud)
    return str(path)


def test_run_fills_the_table_and_a_row_opens_in_the_3d_view(qtbot, cloud_file, tmp_path):
    viewer = _Viewer()
    qtbot.addWidget(viewer)
    dialog = StudyDialog(viewer, cloud_file)
    qtbot.addWidget(dialog)
    dialog.sparse_n.setValue(300)
    dialog.out_dir.setText(str(tmp_path))
    with qtbot.waitSignal(dialog.runner.finished, timeout=120000):
        qtbot.mouseClick(dialog.run_button, QtCore.Qt.MouseButton.LeftButton)
        assert not dialog.run_button.isEnabled() and dialog.cancel_button.isEnabled()
    assert dialog.error is None, dialog.error
    assert dialog.table.rowCount() == 3
    assert dialog.table.item(0, 0).text() == "cyl (900 pts)"
    assert dialog.table.item(2, 0).text() == "cyl (300 pts)"
    assert "/" in dialog.table.item(1, 2).text()
    assert dialog.progress_bar.value() == 1000
    assert (tmp_path / "study.md").is_file()
    qtbot.mouseClick(dialog.open_buttons[2], QtCore.Qt.MouseButton.LeftButton)
    cloud, skeletal, curve, evaluation = viewer.opened[-1]
    assert len(cloud) == 300 and skeletal.shape == (300, 3) and curve.n_vertices > 1
    assert evaluation is dialog.result.rows[2].evaluation  # the stored result, not a recomputation
    assert dialog.run_button.isEnabled() and not dialog.cancel_button.isEnabled()


def test_cancel_stops_the_run_without_a_result(qtbot, cloud_file):
    dialog = StudyDialog(None, cloud_file)
    qtbot.addWidget(dialog)
    with qtbot.waitSignal(dialog.runner.finished, timeout=60000):
        dialog.start()
        dialog.cancel_button.click()
    assert dialog.result is None
    assert dialog.status.text() == "cancelled"
    assert dialog.table.rowCount() == 0


def test_rows_cannot_be_opened_without_a_viewer_that_supports_it(qtbot, cloud_file):
    dialog = StudyDialog(None, cloud_file)
    qtbot.addWidget(dialog)
    dialog.noise.setValue(0.0)
    dialog.sparse_mode.setCurrentIndex(1)
    dialog.grid.setValue(0.5)
    assert dialog.settings()["grid"] == 0.5 and dialog.settings()["sparse"] is None
    assert dialog.settings()["noise"] is None and dialog.settings()["base_grid"] is None
    with qtbot.waitSignal(dialog.runner.finished, timeout=120000):
        dialog.start()
    assert dialog.table.rowCount() == 2
    assert not dialog.open_buttons[0].isEnabled()


def test_a_bad_skeleton_command_is_reported_in_the_dialog(qtbot, cloud_file):
    dialog = StudyDialog(None, cloud_file)
    qtbot.addWidget(dialog)
    dialog.skeleton_cmd.setText("echo {in}")
    with qtbot.waitSignal(dialog.runner.finished, timeout=60000):
        dialog.start()
    assert dialog.result is None
    assert "out_skeletal" in dialog.error and dialog.status.text().startswith("failed:")
