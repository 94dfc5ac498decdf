"""The far cloud drawn once into the view's background (app/view/cloud_layer.py, docs/performance.md
6.10 "The frame of an edit"): once the view is idle its image is made; a frame of the skeleton alone
then draws the near points over it and is the same picture to the bit as the whole cloud's; a moved
camera or a coloured cloud draws the whole cloud again."""

from __future__ import annotations

import numpy as np
import pytest

pytestmark = [pytest.mark.gui, pytest.mark.window(size=(900, 650))]


def _settle(qtbot, w) -> None:
    qtbot.waitUntil(lambda: not w.session.runner.running and not w.view.render_pending, timeout=60000)


def _frame(w) -> np.ndarray:
    """The view's frame as painted (RGB), drawn now."""
    from PySide6 import QtGui

    plotter = w.view.plotter
    plotter.repaint()
    img = plotter.grabFramebuffer().convertToFormat(QtGui.QImage.Format.Format_RGB888)
    rows = np.frombuffer(img.constBits(), np.uint8).reshape(img.height(), img.bytesPerLine())
    return rows[:, : img.width() * 3].reshape(img.height(), img.width(), 3).copy()


def _whole(w) -> np.ndarray:
    """The same frame with the whole cloud drawn (the image kept for the next frame)."""
    w.view._picture = True
    try:
        return _frame(w)
    finally:
        w.view._picture = False


@pytest.fixture
def shown(window, qtbot):
    from skelcore import shapes
    from skelcore.curve import CurveSkeleton

    y = shapes.y_shape(60_000, seed=0)
    curve = CurveSkeleton.from_raw(y.curve_vertices, y.curve_edges)
    window.session.show_arrays(y.cloud, None, curve)
    assert window.session.start_evaluation()
    _settle(qtbot, window)
    if not window.view.plotter.software_gl:
        pytest.skip("the cloud's image is used under software GL only")
    return window, curve


def test_a_frame_over_the_image_is_the_whole_clouds_frame(shown, qtbot):
    w, _curve = shown
    layer = w.view._cloud_layer
    assert layer.builds >= 1 and w.scene.evaluation is not None
    over = _frame(w)
    assert layer.applied and 0 < len(layer._near) < 0.8 * w.scene.cloud.n_points  # far points left out
    whole = _whole(w)
    assert not layer.applied
    assert np.array_equal(over, whole)
    assert (over != 255).any(axis=2).sum() > 1000  # a picture, not a blank view


def test_an_edits_recoloured_frame_uses_the_image_and_is_exact(shown, qtbot):
    w, curve = shown
    layer = w.view._cloud_layer
    builds = layer.builds
    applied: list[bool] = []
    w.session.scores_shown.connect(lambda _ev: w.view.after_render(lambda: applied.append(layer.applied)))
    w.edits.set_active(True)
    # a tip's edge: the curve stays in one piece (an inner edge would split it, and the broken curve's
    # wide halo, a new skeleton element off the image's near pixels, draws the whole cloud again)
    degree = np.bincount(np.asarray(curve.edges).ravel())
    tip_edge = next(e for e in np.asarray(curve.edges) if min(degree[e]) == 1)
    w.edits.select("edge", tuple(int(v) for v in tip_edge))
    w.actions_by_name["edit_delete"].trigger()
    qtbot.waitUntil(lambda: bool(applied), timeout=60000)
    assert applied == [True]  # the recoloured frame drew the near points only
    _settle(qtbot, w)
    assert "disconnected" not in {x.code for x in w.scene.evaluation.warnings}
    assert layer.builds == builds  # the deleted edge lay where the curve was: the same image
    over = _frame(w)
    assert layer.applied and np.array_equal(over, _whole(w))


def test_a_moved_camera_or_a_coloured_cloud_draws_the_whole_cloud(shown, qtbot):
    w, _curve = shown
    layer = w.view._cloud_layer
    _frame(w)
    assert layer.applied
    builds = layer.builds
    w.view.plotter.renderer.GetActiveCamera().Azimuth(20)
    _frame(w)
    assert not layer.applied and layer.build_pending and w.view.render_pending
    renders, paints = [], []
    w.view.plotter.ren_win.AddObserver("EndEvent", lambda *_a: renders.append(1))
    painted = w.view.plotter.on_frame
    w.view.plotter.on_frame = lambda: (paints.append(1), painted())
    _settle(qtbot, w)
    qtbot.wait(50)
    assert layer.builds == builds + 1 and layer.applied  # set while idle, for the next frame
    assert len(renders) == 1 and not paints  # the far points' render, never shown, no repaint asked
    assert np.array_equal(_frame(w), _whole(w)) and layer.applied is False  # _whole turned it off last
    _frame(w)
    assert layer.applied
    w.view.set_cloud_values(np.linspace(0, 1, w.scene.cloud.n_points))  # coloured: order matters
    _settle(qtbot, w)
    _frame(w)
    assert not layer.applied and not layer.build_pending
    assert w.view._meshes["cloud"].n_verts == w.scene.cloud.n_points


def test_a_lines_actors_footprint_is_its_line_width(shown, qtbot):
    """The curve's edges drawn as lines cover their line width, not their (undrawn) point size: fewer
    near points for every frame; drawn as points, the point size counts again."""
    from skelscope.view.cloud_layer import footprint_points

    w, _curve = shown
    edges = w.view._actors["curve-edges"]
    prop = edges.GetProperty()
    ren = w.view.plotter.renderer
    assert prop.GetPointSize() > prop.GetLineWidth()
    x, _y, half = footprint_points(ren, edges)
    assert len(x) > edges.GetMapper().GetInput().GetNumberOfPoints() and half == 0.5 * prop.GetLineWidth()
    prop.SetRepresentationToPoints()
    try:
        assert footprint_points(ren, edges)[2] == 0.5 * prop.GetPointSize()
    finally:
        prop.SetRepresentationToWireframe()
    vertices = w.view._actors["curve-vertices"]
    assert footprint_points(ren, vertices)[2] == 0.5 * vertices.GetProperty().GetPointSize()
