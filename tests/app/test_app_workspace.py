"""The workspace under Xvfb: closing and swapping layers, a new cloud over a skeleton, complete-set
drops, stale results, the Study's thresholds, named exports that ask before replacing."""

from __future__ import annotations

import os

import numpy as np
import pytest
from PySide6 import QtCore, QtGui, QtWidgets

import skelcore
from shape_files import write_shape_files
from skelcore import shapes

pytestmark = [pytest.mark.gui, pytest.mark.window(size=(1200, 800), dialogs="record", questions="default")]


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    return write_shape_files(tmp_path_factory.mktemp("y"), shapes.y_shape(1500, seed=3))


@pytest.fixture(scope="module")
def other_files(tmp_path_factory):
    return write_shape_files(tmp_path_factory.mktemp("torus"), shapes.torus(900, seed=2), stem="torus")


@pytest.fixture(scope="module")
def evaluation(files):
    from skelcore.io import load_cloud, load_curve, load_points

    return skelcore.evaluate(load_cloud(files["cloud"]), load_points(files["skeletal"]), load_curve(files["curve"]),
                             inputs=dict(files))


def _show(window, evaluation):
    window.session._evaluated_layers = (window.scene.cloud, window.scene.skeletal, window.scene.curve)
    window.session._task_succeeded("evaluation", evaluation)


def _drop(widget, paths):
    mime = QtCore.QMimeData()
    mime.setUrls([QtCore.QUrl.fromLocalFile(p) for p in paths])
    pos = QtCore.QPointF(widget.width() / 2, widget.height() / 2)
    QtWidgets.QApplication.sendEvent(widget, QtGui.QDragEnterEvent(
        pos.toPoint(), QtCore.Qt.DropAction.CopyAction, mime, QtCore.Qt.MouseButton.LeftButton,
        QtCore.Qt.KeyboardModifier.NoModifier))
    QtWidgets.QApplication.sendEvent(widget, QtGui.QDropEvent(
        pos, QtCore.Qt.DropAction.CopyAction, mime, QtCore.Qt.MouseButton.LeftButton, QtCore.Qt.KeyboardModifier.NoModifier))


def test_layers_close_from_the_file_menu_and_the_panel_and_all_at_once(window, files):
    w = window
    w.session.load_files([files["cloud"], files["skeletal"], files["curve"]])
    assert w.actions_by_name["close_curve"].isEnabled() and not w.view.hint_visible
    w.actions_by_name["close_curve"].trigger()
    assert w.scene.curve is None and "curve-edges" not in w.view._actors
    assert not w.actions_by_name["close_curve"].isEnabled() and not w.display.remove["curve"].isEnabled()
    w.display.remove["skeletal"].click()
    assert w.scene.skeletal is None and "skeletal" not in w.view._actors
    w.session.load_files([files["skeletal"], files["curve"]])
    w.actions_by_name["close_all"].trigger()
    assert w.scene.layers == {} and w.view._actors == {} and w.view.hint_visible
    assert w.windowTitle() == "SkelScope" and not w.actions_by_name["close_all"].isEnabled()


def test_swap_roles_from_the_display_panel(window, files):
    w = window
    # loaded the wrong way round: the skeletal set as the cloud
    assert w.session.load_as("cloud", files["skeletal"]) and w.session.load_as("skeletal", files["cloud"])
    w.display.swap.click()
    assert w.scene.cloud.path == files["cloud"] and w.scene.skeletal.path == files["skeletal"]
    assert w.view._sources["skeletal"] is w.scene.skeletal.points


def test_a_new_cloud_over_a_skeleton_asks_clears_by_default_and_refits_the_camera(window, files, other_files):
    w = window
    w.session.load_files([files["cloud"], files["skeletal"], files["curve"]])
    w.view.image()
    before = w.view.camera_state()
    assert w.session.load_as("cloud", other_files["cloud"])
    question, options = w.questions[-1]
    assert "keep" in question and options[0] == "clear it"
    assert w.scene.skeletal is None and w.scene.curve is None and w.scene.cloud.n_points == 900
    w.view.image()
    after = w.view.camera_state()
    assert not np.allclose(before["focal_point"], after["focal_point"])
    _assert_fits(w, w.scene.cloud.points)
    # "keep it" keeps the skeleton
    w.session.load_as("skeletal", other_files["skeletal"])
    w.session.ask = lambda q, o: "keep it"
    w.session.load_as("cloud", other_files["cloud"])
    assert w.scene.skeletal is not None


def _assert_fits(w, points):
    """Every point is drawn inside the view and left of the colour bar."""
    from skelscope.view.camera import FIT_X
    from skelscope.view.picking import pick_layout, project_to_display

    ren = w.view.plotter.renderer
    x, y, _ = project_to_display(ren, pick_layout(points))
    width, height = ren.GetSize()
    assert x.min() >= 0 and y.min() >= 0 and y.max() <= height
    assert x.max() <= (FIT_X[1] + 1) / 2 * width + 1


def test_the_first_frame_fits_all_the_data(window, files):
    w = window
    w.session.load_files([files["cloud"], files["skeletal"], files["curve"]])
    w.view.image()
    _assert_fits(w, w.scene.cloud.points)
    w.view.standard_view("xy")  # the Y's arms spread across the view
    w.view.image()
    _assert_fits(w, w.scene.cloud.points)


def test_a_complete_set_dropped_on_a_loaded_window_replaces_it_without_a_question(window, files, other_files):
    w = window
    w.session.load_files([files["cloud"], files["skeletal"], files["curve"]])
    _drop(w.view.widget, [other_files["skeletal"], other_files["curve"], other_files["cloud"]])
    assert w.questions == []
    assert (w.scene.cloud.path, w.scene.skeletal.path, w.scene.curve.path) == (
        other_files["cloud"], other_files["skeletal"], other_files["curve"])


def test_an_ambiguous_drop_defaults_to_skipping_the_file(window, files, other_files):
    w = window
    w.session.load_files([files["cloud"], files["skeletal"]])
    _drop(w.view.widget, [other_files["skeletal"]])  # 900 points on a 1500-point cloud
    assert "900 points but the cloud has 1500" in w.questions[-1][0]
    assert w.scene.cloud.path == files["cloud"] and w.scene.skeletal.path == files["skeletal"]


def test_changed_settings_mark_the_results_stale_until_re_run(window, files, evaluation, qtbot, monkeypatch):
    w = window
    w.session.load_files([files["cloud"], files["skeletal"], files["curve"]])
    _show(w, evaluation)
    assert not w.summary.rerun.isVisible() and not w.summary.is_greyed()
    assert "eps*" in w.summary.details.text()
    w.settings_panel.smooth_k.setValue(w.settings_panel.smooth_k.value() + 2)
    assert w.summary.stale == "settings changed" and w.summary.rerun.isVisible() and w.summary.is_greyed()
    assert "re-run" in w.summary.rerun.text()
    w.summary.beta_star.setValue(0.5)  # thresholds re-score at once: they never make results stale
    w.settings_panel.smooth_k.setValue(w.settings_panel.smooth_k.value() - 2)
    assert w.summary.stale == "" and not w.summary.rerun.isVisible() and not w.summary.is_greyed()
    w.session._shown_correspondence = w.settings_panel.correspondence()  # as after a run from the window
    other = [w.settings_panel.correspondence_choice.itemData(i) for i in range(w.settings_panel.correspondence_choice.count())]
    other = [k for k in other if k != w.settings_panel.correspondence()]
    if other:
        w.settings_panel.set_correspondence(other[0])
        assert w.summary.stale == "settings changed"
    w.settings_panel.curve_samples.setValue(50)
    started = []
    monkeypatch.setattr(w.session, "start_evaluation", lambda *a: started.append(1))
    w.summary.rerun_requested.disconnect()
    w.summary.rerun_requested.connect(w.session.start_evaluation)
    w.summary.rerun.click()
    assert started == [1]


def test_changed_inputs_clear_the_results_and_no_text_describes_them(window, files, evaluation, other_files):
    w = window
    w.session.load_files([files["cloud"], files["skeletal"], files["curve"]])
    _show(w, evaluation)
    assert "evaluated in" in w.summary.details.text()
    w.statusBar().showMessage("evaluation done in 2.80 s", 8000)
    w.session.load_as("skeletal", files["skeletal"])  # (closing the curve alone keeps the skeletal results)
    assert "evaluation done" not in w.statusBar().currentMessage()
    assert w.scene.evaluation is None
    assert "evaluated in" not in w.summary.details.text() and "eps*" not in w.summary.details.text()
    assert w.summary.cell_text("boundedness", "skeletal points") == "—"
    assert w.summary.stale == "inputs changed" and w.summary.rerun.isVisible()


def test_the_study_uses_the_windows_thresholds_and_a_row_opens_its_stored_result(window, files, qtbot, monkeypatch):
    w = window
    w.session.load_as("cloud", files["cloud"])
    w.summary.c_star.setValue(0.6)
    w.settings_panel.boundedness_method.setCurrentText("paper")
    w.actions_by_name["study"].trigger()
    dialog = w._study_dialog
    assert dialog.params.c_star == pytest.approx(0.6) and dialog.params.boundedness_method == "paper"
    assert "c* = 0.6" in dialog.thresholds.text()
    dialog.close()
    # a stored row: shown with its evaluation, nothing recomputed
    sh = shapes.y_shape(600, seed=1)
    from skelcore.curve import CurveSkeleton

    curve = CurveSkeleton.from_raw(sh.curve_vertices, sh.curve_edges)
    stored = skelcore.evaluate(sh.cloud, sh.skeletal, curve, skelcore.Params(c_star=0.6))
    monkeypatch.setattr(skelcore, "evaluate", lambda *a, **k: pytest.fail("recomputed"))
    w.session.auto_evaluate = True
    w.open_variant(sh.cloud, sh.skeletal, curve, stored)
    assert w.scene.evaluation is stored and not w.session.runner.running
    assert w.summary.c_star.value() == pytest.approx(0.6)


def test_exports_are_named_after_the_data_and_never_replace_without_asking(window, files, evaluation, tmp_path, monkeypatch):
    w = window
    w.session.load_files([files["cloud"], files["skeletal"], files["curve"]])
    _show(w, evaluation)
    written = w.export_ply(str(tmp_path))
    assert os.path.basename(written[0]) == "y_cloud_skeletal.ply"
    stamp = os.path.getmtime(written[0])
    with pytest.raises(FileExistsError):
        w.export_ply(str(tmp_path))
    w.export_results(str(tmp_path / "run.json"))
    with pytest.raises(FileExistsError):
        w.export_results(str(tmp_path / "run.json"))
    # the dialog asks; "No" (the default) keeps the files
    asked = []
    monkeypatch.setattr(QtWidgets.QFileDialog, "getExistingDirectory", lambda *a, **k: str(tmp_path))
    monkeypatch.setattr(QtWidgets.QMessageBox, "question",
                        lambda *a, **k: asked.append(a[2]) or QtWidgets.QMessageBox.StandardButton.No)
    w.export_ply_dialog()
    assert asked and "y_cloud_skeletal.ply" in asked[0] and os.path.getmtime(written[0]) == stamp
    monkeypatch.setattr(QtWidgets.QMessageBox, "question", lambda *a, **k: QtWidgets.QMessageBox.StandardButton.Yes)
    w.export_ply_dialog()
    assert os.path.getmtime(written[0]) >= stamp and w.dialogs == []


def test_the_picture_dialog_has_file_scale_background_and_colour_bar(window, files, evaluation, tmp_path, monkeypatch):
    from skelscope.picture_dialog import PictureDialog

    w = window
    w.session.load_files([files["cloud"], files["skeletal"], files["curve"]])
    _show(w, evaluation)
    target = tmp_path / "fig"

    def run(dialog):
        assert dialog.path.text().endswith("y_cloud_boundedness.png")
        dialog.path.setText(str(target))
        dialog.scale.setValue(2)
        dialog.set_background("transparent")
        dialog.colour_bar.setChecked(False)
        return QtWidgets.QDialog.DialogCode.Accepted

    monkeypatch.setattr(PictureDialog, "exec", run)
    w.screenshot_dialog()
    from matplotlib.image import imread

    img = imread(str(target) + ".png")
    view = w.view.widget
    assert img.shape == (2 * view.height(), 2 * view.width(), 4) and img[..., 3].min() == 0
    assert "fig.png" in w.statusBar().currentMessage()


def test_the_orientation_axes_keep_a_small_corner_the_data_stays_out_of(window, tmp_path):
    """The axes sit in an AXES_PIXELS square of the lower-left corner (pyvista's fifth of the view drew
    them over an arm of the Y at 1920 x 1080), and a fit keeps every point out of that square: a rod
    from the lower left to the upper right, seen from above, ends in the corner unless the fit zooms
    out for it."""
    from skelcore.io import write_points_ply
    from skelscope.view.camera import AXES_PIXELS
    from skelscope.view.picking import pick_layout, project_to_display

    w = window
    w.view.image()
    ren = w.view.plotter.renderer
    width, height = ren.GetSize()
    rng = np.random.default_rng(0)  # along the diagonal of the area a fit fills (FIT_X x FIT_Y)
    rod = rng.uniform(-1.0, 1.0, size=(3000, 1)) * [0.835 * width, 0.92 * height, 0.0] / height
    rod += rng.normal(scale=0.002, size=rod.shape)
    write_points_ply(tmp_path / "rod.ply", rod)
    w.session.load_as("cloud", str(tmp_path / "rod.ply"))
    assert w.scene.style["axes"]
    w.view.standard_view("xy")
    w.view.image()
    side = AXES_PIXELS * w.view.plotter.devicePixelRatioF()
    x0, y0, x1, y1 = ren.axes_widget.GetViewport()
    assert (x0, y0) == (0.0, 0.0) and x1 * width == pytest.approx(side) and y1 * height == pytest.approx(side)
    x, y, _ = project_to_display(ren, pick_layout(rod))
    assert not np.any((x < side) & (y < side))  # none under the axes ...
    assert min(x.min(), y.min()) < 1.5 * side  # ... and the rod's end just beside them
    w.display.style["axes"].setChecked(False)  # no axes: the fit fills the corner again
    w.view.standard_view("xy")
    w.view.image()
    x, y, _ = project_to_display(ren, pick_layout(rod))
    assert np.any((x < side) & (y < side))
