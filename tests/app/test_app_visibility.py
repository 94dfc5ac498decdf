"""Full detail at rest through the points that can show (app/view/visibility.py, app/view/culling.py):
against a brute-force depth-tested rasterization of GL points, then in the window under Xvfb: the
picture pixel for pixel the same as drawing every point, picks on the real point ids, pictures at
another scale drawing every point, and VTK's interaction rendering through the view's paint only."""

from __future__ import annotations

import numpy as np
import pytest

from skelscope.view.visibility import ScreenPoints, visible_points


def _raster(layers, width, height, keep=None):
    """Brute force: each layer's points drawn in order as GL draws flat points (the pixels whose
    centres lie in [pos - size/2, pos + size/2)), opaque ones depth-tested with LEQUAL, then the
    translucent ones against their depth. Returns the opaque owner (layer, index) of every pixel and,
    per layer, the points that pass a depth test (for a translucent layer: those blended in)."""
    depth = np.full((height, width), np.inf)
    owner = np.full((height, width, 2), -1)
    reach: list[set[int]] = [set() for _ in layers]
    for pass_opaque in (True, False):  # the opaque pass first, then the translucent one against its depth
        for li, p in enumerate(layers):
            if p.opaque != pass_opaque:
                continue
            for i in (range(len(p.x)) if keep is None else keep[li]):
                cols = [c for c in range(width) if p.x[i] - p.size / 2 <= c + 0.5 < p.x[i] + p.size / 2]
                rows = [r for r in range(height) if p.y[i] - p.size / 2 <= r + 0.5 < p.y[i] + p.size / 2]
                for r in rows:
                    for c in cols:
                        if p.z[i] <= depth[r, c]:
                            reach[li].add(int(i))
                            if p.opaque:
                                depth[r, c] = p.z[i]
                                owner[r, c] = (li, i)
    return owner, reach


@pytest.mark.parametrize("seed", range(4))
def test_the_points_kept_draw_the_same_pixels_as_all_of_them(seed):
    rng = np.random.default_rng(seed)
    width, height = 40, 30
    layers = []
    for size, opaque, n in ((6, True, 400), (2, True, 300), (1, False, 300), (3, False, 100)):
        x = rng.uniform(-4, width + 4, n)
        y = rng.uniform(-4, height + 4, n)
        x[: n // 10] = np.round(x[: n // 10]) + 0.5 * (1 - size % 2)  # some exactly on a pixel boundary
        z = rng.uniform(-1, 1, n).round(2)  # ties between points
        layers.append(ScreenPoints(x, y, z, size, opaque))
    kept = visible_points(layers, width, height)
    owner, reach = _raster(layers, width, height)
    owner_kept, _ = _raster(layers, width, height, keep=kept)
    assert np.array_equal(owner, owner_kept)  # every pixel won by the same point
    for li, (k, r) in enumerate(zip(kept, reach)):
        if layers[li].opaque:  # the points that own a pixel at the end
            r = {int(i) for i in owner[..., 1][owner[..., 0] == li]}
        assert r <= set(k.tolist()), f"layer {li}: a point that shows was dropped"
        assert np.all(np.diff(k) > 0)  # in their drawing order
        assert len(k) <= 1.25 * len(r) + 20, f"layer {li}: {len(k)} kept for {len(r)} that show"
    assert len(kept[0]) < 0.6 * len(layers[0].x)  # the big opaque points hide many


def test_points_off_the_view_or_behind_the_camera_are_dropped():
    x = np.array([5.0, -20.0, 5.0, 50.0, 1e12, np.nan])
    z = np.array([0.0, 0.0, np.inf, 0.0, 0.0, np.nan])
    kept = visible_points([ScreenPoints(x, np.full(6, 5.0), z, 2, True)], 10, 10)
    assert kept[0].tolist() == [0]


def test_a_wide_rounding_bound_keeps_every_point_that_could_show():
    """Far zoomed in, a point's display position is only known to within more than a pixel: it hides
    nothing and is kept wherever its square could fall."""
    front = ScreenPoints(np.array([2.0, 8.0]), np.array([5.0, 5.0]), np.array([0.0, 0.0]), 4, True)  # x 0-3, 6-9
    behind = ScreenPoints(np.array([5.0, 5.0]), np.array([5.0, 5.0]), np.array([0.5, 0.5]), 2, True,
                          edge=np.array([0.0, 1.6]))  # the first covers x 4-5; the second may cover 3-4 or 5-6
    assert visible_points([front, behind], 10, 10)[1].tolist() == [0, 1]
    behind.x[:] = 4.0  # x 3-4: hidden at column 3 only, visible at column 4
    assert visible_points([front, behind], 10, 10)[1].tolist() == [0, 1]


@pytest.fixture
def big(window, monkeypatch):
    """The window showing a sphere of 30k points with a skeletal set inside it, both 'big' (over a
    lowered LOD_POINTS): so both are thinned at rest."""
    import skelscope.view.scene_view as scene_view
    from skelcore import shapes

    monkeypatch.setattr(scene_view, "LOD_POINTS", 2000)
    cloud = shapes.sphere_surface(30_000, seed=0)
    skeletal = 0.3 * cloud + np.random.default_rng(1).normal(scale=0.01, size=cloud.shape)
    window.scene.set_cloud(cloud)
    window.scene.set_skeletal(skeletal)
    return window, cloud, skeletal


def _every_point(view, monkeypatch):
    """The view's picture with every point drawn (thinning is for software GL only)."""
    monkeypatch.setattr(view.plotter, "software_gl", False)
    try:
        return view.image()
    finally:
        monkeypatch.setattr(view.plotter, "software_gl", True)


@pytest.mark.gui
@pytest.mark.window(size=(900, 700))
def test_at_rest_the_big_layers_draw_only_what_shows_and_the_picture_is_the_same(big, monkeypatch):
    window, cloud, skeletal = big
    view = window.view
    assert view.plotter.software_gl
    camera = view.plotter.renderer.GetActiveCamera()
    for turn in range(3):
        thin = view.image()
        drawn = dict(view._resting.drawn)
        assert np.array_equal(thin, _every_point(view, monkeypatch)), f"turn {turn}"
        assert drawn["skeletal"] < len(skeletal) / 4
        assert drawn["cloud"] == len(cloud)  # translucent, in view: all drawn (few would drop)
        camera.Azimuth(40)
        camera.Elevation(25)
        camera.OrthogonalizeViewUp()
    camera.Zoom(5.0)  # most of the translucent cloud off the view: thinned too
    thin = view.image()
    assert view._resting.drawn["cloud"] < len(cloud) / 4
    assert np.array_equal(thin, _every_point(view, monkeypatch))
    camera.Zoom(0.2)
    view.image()
    behind_glass = view._resting.drawn["skeletal"]
    window.scene.set_opacity("cloud", 1.0)  # an opaque cloud hides its own back and most of the skeletal set
    values = np.linspace(0.0, 1.0, len(cloud))
    values[::50] = np.nan  # invalid values: magenta
    view.set_cloud_values(values)
    thin = view.image()
    assert view._resting.drawn["cloud"] < len(cloud) * 0.7 and view._resting.drawn["skeletal"] < behind_glass
    assert np.array_equal(thin, _every_point(view, monkeypatch))
    assert np.all(thin[..., :3] == (255, 0, 255), axis=-1).sum() > 100


@pytest.mark.gui
@pytest.mark.window(size=(900, 700))
def test_a_pick_among_thinned_points_names_the_real_point_and_other_scales_draw_every_point(big):
    from skelscope.view.picking import pick_layout, project_to_display

    window, cloud, skeletal = big
    view = window.view
    window.scene.set_visible("cloud", False)
    view.image()
    mesh = view._meshes["skeletal"]
    shown = np.asarray(mesh.verts).reshape(-1, 2)[:, 1]
    assert 0 < len(shown) < len(skeletal) / 4
    x, y, z = project_to_display(view.plotter.renderer, pick_layout(skeletal[shown]))
    front = int(np.argmin(z))  # the nearest point drawn: on top at its centre
    info = view.pick_display(float(x[front]), float(y[front]))
    assert info is not None and info["index"] == int(shown[front]) and info["index"] >= len(shown) // 2
    assert np.allclose(info["xyz"], skeletal[info["index"]])
    big_picture = view.image(scale=2)
    assert big_picture.shape[1] == 2 * view.image().shape[1]
    view.image(scale=2)
    assert view._resting.drawn["skeletal"] == len(skeletal)  # another scale: every point
    view.image()
    assert view._resting.drawn["skeletal"] == len(shown)  # the view's own: thinned again


@pytest.mark.gui
def test_vtk_interaction_draws_through_the_paint_once_per_frame(big, qtbot):
    """A drag's release (VTK's interactor style renders at its end) and the view's full-detail frame
    are one render, not two: VTK's own render requests wait for the paint."""
    from PySide6 import QtCore

    window = big[0]
    view = window.view
    frames: list[bool] = []
    view.plotter.ren_win.AddObserver("EndEvent", lambda *a: frames.append(bool(view._actors["cloud"].GetVisibility())))
    view.request_render()
    qtbot.waitUntil(lambda: not view.render_pending and bool(frames), timeout=20000)
    qtbot.wait(50)
    frames.clear()
    view.plotter.ren_win.GetInteractor().Render()  # what the interactor style asks on every move
    assert frames == []  # nothing drawn at once
    qtbot.waitUntil(lambda: len(frames) == 1, timeout=20000)
    centre = view.widget.rect().center()
    qtbot.mousePress(view.widget, QtCore.Qt.MouseButton.LeftButton, pos=centre)
    assert view.moving
    frames.clear()
    qtbot.mouseRelease(view.widget, QtCore.Qt.MouseButton.LeftButton, pos=centre + QtCore.QPoint(30, 0))
    qtbot.waitUntil(lambda: bool(frames) and not view.render_pending, timeout=20000)
    qtbot.wait(100)
    assert frames == [True]  # full detail, drawn once


@pytest.mark.gui
@pytest.mark.window(size=(900, 700))
def test_software_gl_blends_the_translucent_cloud_in_order_with_the_same_picture(big):
    window, _cloud, _skeletal = big
    view = window.view
    renderer = view.plotter.renderer
    assert view.plotter.software_gl and not renderer.GetUseOIT()
    plain = view.image().astype(int)
    renderer.SetUseOIT(True)  # VTK's default: order-independent translucency
    try:
        oit = view.image().astype(int)
    finally:
        renderer.SetUseOIT(False)
    assert np.abs(plain - oit).max() <= 2  # a uniform translucent layer: the blend order does not matter
    assert (np.abs(plain - oit).max(axis=-1) > 0).mean() < 0.2
