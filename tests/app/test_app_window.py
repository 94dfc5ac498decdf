"""The main window under Xvfb: loading through the API and by drag-and-drop, error dialogs, the
render checked by content (cloud grey, colour-map colours, magenta exactly for NaN), picking."""

from __future__ import annotations

import math

import numpy as np
import pytest
from PySide6 import QtCore, QtGui, QtWidgets

from skelcore import shapes
from shape_files import write_shape_files
from skelcore.colors import SKELETAL_COLOR, lookup_table
from skelcore.io import write_points_ply
from skelscope.loading import REPLACE_CLOUD

pytestmark = [pytest.mark.gui, pytest.mark.window(size=(1200, 800), dialogs="record")]


@pytest.fixture
def files(tmp_path):
    return write_shape_files(tmp_path, shapes.y_shape(1500, seed=3))


def _drop(widget: QtWidgets.QWidget, paths: list[str]) -> QtGui.QDropEvent:
    mime = QtCore.QMimeData()
    mime.setUrls([QtCore.QUrl.fromLocalFile(p) for p in paths])
    pos = QtCore.QPointF(widget.width() / 2, widget.height() / 2)
    enter = QtGui.QDragEnterEvent(pos.toPoint(), QtCore.Qt.DropAction.CopyAction, mime,
                                  QtCore.Qt.MouseButton.LeftButton, QtCore.Qt.KeyboardModifier.NoModifier)
    QtWidgets.QApplication.sendEvent(widget, enter)
    assert enter.isAccepted()
    drop = QtGui.QDropEvent(pos, QtCore.Qt.DropAction.CopyAction, mime, QtCore.Qt.MouseButton.LeftButton,
                            QtCore.Qt.KeyboardModifier.NoModifier)
    QtWidgets.QApplication.sendEvent(widget, drop)
    return drop


def _rgb(img: np.ndarray) -> np.ndarray:
    return np.asarray(img)[..., :3].reshape(-1, 3).astype(int)


def _count(img: np.ndarray, colour) -> int:
    return int(np.all(_rgb(img) == np.asarray(colour), axis=1).sum())


def _is_grey(img: np.ndarray) -> int:
    px = _rgb(img)
    spread = px.max(axis=1) - px.min(axis=1)
    return int(((spread <= 6) & (px[:, 0] > 90) & (px[:, 0] < 235)).sum())


def test_files_load_through_the_api_with_roles(window, files):
    assert window.session.load_as("cloud", files["cloud"])
    done = window.session.load_files([files["curve"], files["skeletal"]])
    assert sorted(role for role, _ in done) == ["curve", "skeletal"]
    scene = window.scene
    assert scene.cloud.n_points == scene.skeletal.n_points == 1500
    assert scene.curve.edges.shape[1] == 2 and scene.curve.path == files["curve"]
    assert window.recent_files()[0].endswith("y_skeletal.ply") or window.recent_files()[0].endswith("y_curve.ply")
    assert window.dialogs == []


def test_drop_of_several_files_on_the_3d_view_assigns_roles_not_pyvistas_reader(window, files, qtbot):
    n_actors_before = len(window.view.plotter.renderer.actors)
    drop = _drop(window.view.widget, [files["curve"], files["cloud"], files["skeletal"]])
    assert drop.isAccepted()
    scene = window.scene
    assert scene.cloud.path == files["cloud"]
    assert scene.skeletal.path == files["skeletal"]
    assert scene.curve.path == files["curve"]
    # cloud, skeletal points, curve edges, curve vertices: our actors, not a pyvista.read() mesh
    assert set(window.view._actors) == {"cloud", "skeletal", "curve-edges", "curve-vertices"}
    assert len(window.view.plotter.renderer.actors) >= n_actors_before + 4


def test_drop_on_a_side_panel_loads_too(window, files):
    _drop(window, [files["cloud"]])
    assert window.scene.cloud is not None


def test_corrupt_file_gives_a_dialog_and_the_window_and_loaded_data_survive(window, files, tmp_path):
    assert window.session.load_as("cloud", files["cloud"])
    bad = tmp_path / "broken.ply"
    bad.write_bytes(open(files["cloud"], "rb").read()[:300])
    assert not window.session.load_as("skeletal", str(bad))
    assert len(window.dialogs) == 1 and "broken.ply" in window.dialogs[0] and "\n" not in window.dialogs[0]
    assert window.scene.cloud.path == files["cloud"] and window.scene.skeletal is None
    window.session.load_files([str(bad), files["skeletal"]])
    assert len(window.dialogs) == 2
    assert window.scene.skeletal.path == files["skeletal"]
    assert window.isVisible()


def test_render_shows_the_cloud_grey_and_colour_map_colours(window, files, qtbot):
    window.session.load_files([files["cloud"], files["skeletal"]])
    plain = window.view.image()
    assert _is_grey(plain) > 200  # the cloud
    assert _count(plain, SKELETAL_COLOR) > 50  # uncoloured skeletal points have their plain colour
    values = np.linspace(0.0, 1.0, window.scene.skeletal.n_points)
    window.scene.skeletal.add_scalar_quantity("boundedness", values)
    window.scene.set_metric("boundedness")
    img = window.view.image()
    assert _count(img, SKELETAL_COLOR) == 0
    lut = lookup_table("viridis", 256).astype(int)
    # each distinct colour of the picture measured once against the map (a render has few of them)
    colours, counts = np.unique(_rgb(img), axis=0, return_counts=True)
    d = np.abs(colours[:, None, :] - lut[None, :, :]).max(axis=2).min(axis=1)
    assert counts[d <= 3].sum() > 300
    assert _count(img, (255, 0, 255)) == 0  # no NaN, no magenta


def test_magenta_appears_exactly_when_values_are_invalid(window, files):
    window.session.load_files([files["cloud"], files["skeletal"], files["curve"]])
    scene = window.scene
    n = scene.skeletal.n_points
    scene.skeletal.add_scalar_quantity("smoothness", np.full(n, 0.5))
    degrees = scene.curve.curve.degrees()
    scene.curve.add_scalar_quantity("smoothness", np.where(degrees == 2, 0.9, 1.0), location="vertices")
    scene.set_metric("smoothness")
    assert _count(window.view.image(), (255, 0, 255)) == 0
    # docs/metrics.md 4: a curve vertex that is not of degree 2 (the junction of the Y, the three tips) is NaN.
    assert (degrees == 3).sum() == 1
    scene.curve.add_scalar_quantity("smoothness", np.where(degrees == 2, 0.9, math.nan), location="vertices")
    scene.set_metric("smoothness")
    assert _count(window.view.image(), (255, 0, 255)) > 20
    assert "4 invalid" in window.display.invalid.text()
    scene.set_visible("curve", False)
    assert _count(window.view.image(), (255, 0, 255)) == 0


def test_clicking_a_skeletal_point_shows_its_index_coordinates_and_values(window, files, qtbot):
    window.session.load_files([files["cloud"], files["skeletal"]])
    scene = window.scene
    scene.set_visible("cloud", False)
    scene.skeletal.add_scalar_quantity("boundedness", np.linspace(0, 1, scene.skeletal.n_points))
    scene.set_metric("boundedness")
    window.view.image()
    target = int(np.argmax(scene.skeletal.points[:, 1]))  # the tip of the upper arm
    x, y = window.view.world_to_display(scene.skeletal.points[target])
    widget = window.view.widget
    pos = QtCore.QPoint(int(round(x / widget.devicePixelRatioF())), int(round(widget.height() - y / widget.devicePixelRatioF())))
    qtbot.mouseClick(widget, QtCore.Qt.MouseButton.LeftButton, pos=pos)
    info = window.pick.info
    assert info is not None and info["element"] == "skeletal point"
    assert np.linalg.norm(np.asarray(info["xyz"]) - scene.skeletal.points[target]) < 0.05
    assert info["values"]["boundedness"] == pytest.approx(scene.skeletal.quantities["boundedness"].values[info["index"]])
    assert f"#{info['index']}" in window.pick.text.toPlainText()
    assert "pick-marker" in window.view._actors


def test_camera_views_and_parallel_projection(window, files):
    window.session.load_as("cloud", files["cloud"])
    window.view.standard_view("xy")
    assert np.allclose(np.abs(window.view.plotter.camera.direction), [0, 0, 1], atol=1e-6)
    window.actions_by_name["parallel"].trigger()
    assert window.view.parallel_projection
    window.actions_by_name["parallel"].trigger()
    assert not window.view.parallel_projection
    with pytest.raises(ValueError):
        window.view.standard_view("sideways")


def test_help_lists_the_keyboard_shortcuts(window):
    rows = dict(window.shortcut_rows())
    assert rows["Evaluate"] == "F5" and rows["Cancel"] == "Esc" and rows["Reset camera"] == "R"
    assert "Keyboard shortcuts" in rows


def test_vtk_single_key_bindings_do_not_close_the_view(window, files, qtbot):
    window.session.load_as("cloud", files["cloud"])
    qtbot.keyClick(window.view.widget, "q")
    qtbot.keyClick(window.view.widget, "e")
    assert window.isVisible() and not window.view.plotter._closed
    assert window.view.image().std() > 0


def test_ambiguous_drop_asks_and_the_answer_decides_the_role(window, files, tmp_path, monkeypatch):
    window.session.load_files([files["cloud"]])
    other = tmp_path / "other_cloud.ply"
    write_points_ply(other, shapes.cylinder(700, seed=4).cloud)
    asked = []
    answer = {"choice": None}  # None: Enter on the dialog's default

    def get_item(parent, title, question, options, current, editable):
        asked.append(question)
        return (options[current] if answer["choice"] is None else answer["choice"]), True

    monkeypatch.setattr(QtWidgets.QInputDialog, "getItem", get_item)
    _drop(window.view.widget, [str(other)])
    assert asked and "700 points but the cloud has 1500" in asked[0]
    assert window.scene.cloud.path == files["cloud"]  # the default never replaces the loaded cloud
    answer["choice"] = REPLACE_CLOUD
    _drop(window.view.widget, [str(other)])
    assert window.scene.cloud.path == str(other) and window.scene.cloud.n_points == 700


def test_a_study_variant_opens_in_the_3d_view_without_files(window):
    sh = shapes.torus(600, seed=2)
    from skelcore.curve import CurveSkeleton

    window.open_variant(sh.cloud, sh.skeletal, CurveSkeleton.from_raw(sh.curve_vertices, sh.curve_edges))
    scene = window.scene
    assert scene.cloud.n_points == 600 and scene.skeletal.n_points == 600 and scene.curve.curve.n_edges == 32
    assert scene.cloud.path is None and window.actions_by_name["evaluate"].isEnabled()
    window.open_variant(sh.cloud, sh.skeletal, None)
    assert scene.curve is None and "curve-edges" not in window.view._actors


def test_edges_as_tubes_and_display_controls_change_the_actors(window, files):
    window.session.load_files([files["cloud"], files["curve"]])
    view = window.view
    assert view._actors["curve-edges"].mapper.dataset.n_lines > 0
    window.actions_by_name["tubes"].trigger()
    tubes = view._actors["curve-edges"].mapper.dataset
    assert tubes.n_lines == 0 and tubes.n_strips > 0  # triangle strips around each edge
    window.display.size["cloud"].setValue(5)
    window.display.opacity["cloud"].setValue(80)
    assert view._actors["cloud"].prop.point_size == 5 and view._actors["cloud"].prop.opacity == pytest.approx(0.8)
    window.display.visible["cloud"].setChecked(False)
    assert not view._actors["cloud"].GetVisibility()


def test_settings_panel_builds_the_evaluation_parameters(window):
    panel = window.settings_panel
    panel.boundedness_method.setCurrentText("paper")
    panel.k_center.setValue(12)
    panel.curve_samples.setValue(50)
    window.summary.beta_star.setValue(0.6)
    params = window.session.params()
    assert (params.boundedness_method, params.k_center, params.curve_samples) == ("paper", 12, 50)
    assert params.beta_star == pytest.approx(0.6)
    panel.k_center.setValue(0)
    assert window.session.params().k_center is None  # 0 shows "auto": the rule of docs/metrics.md 3


def test_a_dropped_folder_that_is_not_a_compare_run_is_refused_with_one_line(window, files, tmp_path, qtbot):
    folder = tmp_path / "plain_folder"
    folder.mkdir()
    drop = _drop(window.view.widget, [str(folder)])
    assert drop.isAccepted()
    qtbot.waitUntil(lambda: window.dialogs != [], timeout=5000)
    (text,) = window.dialogs
    assert "plain_folder" in text and "not a skelcore compare run" in text and "\n" not in text
    assert window.scene.layers == {}
    # dropped with files: the files load, the folder is named
    _drop(window, [str(folder), files["cloud"]])
    qtbot.waitUntil(lambda: len(window.dialogs) == 2, timeout=5000)
    assert window.scene.cloud.path == files["cloud"] and "plain_folder" in window.dialogs[1]
