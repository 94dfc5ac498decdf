"""Picking and supports, and the stale state: a click means what is drawn on top there; the
picked element stays marked when the metric changes; smoothness has a support (dock and 3-D); the
support's colours stand apart from the skeleton's, the ellipse is drawn in 3-D, every overlay has a
legend entry and the slab plot's legend leaves its data alone; out-of-date results are greyed in the
3-D view and the histogram; closing the curve keeps the skeletal set's results."""

from __future__ import annotations

import numpy as np
import pytest

from skelcore import evaluate, shapes
from skelcore.curve import CurveSkeleton

pytestmark = [pytest.mark.gui, pytest.mark.window(size=(1300, 850))]


@pytest.fixture(scope="module")
def y_eval():
    sh = shapes.y_shape(1500, seed=3)
    curve = CurveSkeleton.from_raw(sh.curve_vertices, sh.curve_edges)
    return sh, curve, evaluate(sh.cloud, sh.skeletal, curve)


def _shown(w, qtbot, sh, skeletal, curve, ev=None):
    w.session.show_arrays(sh.cloud, skeletal, curve, ev)
    w.scene.set_visible("cloud", False)
    w.view.image()  # a frame at the final size: the camera is set
    return w


def _towards_camera(w, xyz, fraction=0.01):
    cam = w.view.plotter.renderer.GetActiveCamera()
    d = np.asarray(cam.GetPosition()) - np.asarray(xyz)
    return np.asarray(xyz) + fraction * d  # nearer the eye, on the same line of sight


def _junction(curve):
    return int(np.flatnonzero(curve.degrees() == 3)[0])


@pytest.mark.parametrize("metric", ["smoothness", "boundedness"])
def test_a_curve_vertex_is_picked_over_a_skeletal_point_hidden_under_it(window, qtbot, y_eval, metric):
    """The junction (drawn magenta for smoothness: no angle at degree 3; plain for boundedness) with
    a skeletal point on the same line of sight, nearer the eye: the click gives the curve vertex."""
    sh, curve, _ = y_eval
    w = window
    j = _junction(curve)
    vertex = curve.vertices[j]
    _shown(w, qtbot, sh, sh.skeletal, curve)
    skeletal = np.vstack([sh.skeletal, _towards_camera(w, vertex)])
    ev = evaluate(sh.cloud, skeletal, curve)
    _shown(w, qtbot, sh, skeletal, curve, ev)
    w.scene.set_metric(metric)
    w.view.image()
    x, y = w.view.world_to_display(vertex)
    info = w.view.pick_display(x, y)
    assert info["element"] == "curve vertex" and info["index"] == j
    if metric == "smoothness":
        assert np.isnan(info["values"]["smoothness"])  # the magenta one
    # a skeletal point with no curve over it is still picked
    lone = int(np.argmax(np.linalg.norm(skeletal[:-1] - vertex, axis=1)))
    far = np.linalg.norm(curve.vertices - skeletal[lone], axis=1).min()
    if far > 0.05:
        x, y = w.view.world_to_display(skeletal[lone])
        got = w.view.pick_display(x, y)
        assert got["element"] == "skeletal point"


def test_switching_the_metric_keeps_the_picked_element_marked(window, qtbot, y_eval):
    sh, curve, ev = y_eval
    w = _shown(window, qtbot, sh, sh.skeletal, curve, ev)
    i = int(np.argmax(sh.skeletal[:, 2]))
    x, y = w.view.world_to_display(sh.skeletal[i])
    info = w.view.pick_display(x, y)  # what a click does: the projection pick, then the window's pick_element
    w.pick_element(info)
    assert w.view.marker_shown
    for metric in ("centeredness", "smoothness", "boundedness"):
        w.scene.set_metric(metric)
        assert w.view.marker_shown and w.view.picked is info and w.pick.info is info
        assert _orange(w.view.image()) > 20  # drawn, not just kept
    w.scene.set_evaluation(ev)  # a new result: values changed, the mark goes
    assert not w.view.marker_shown and _orange(w.view.image()) == 0


def _orange(img) -> int:
    """Pixels of the pick marker's colour (shaded as a sphere: near it, not equal)."""
    from skelcore.colors import PICK_COLOR

    rgb = np.asarray(img)[..., :3].reshape(-1, 3).astype(float)
    return int((np.linalg.norm(rgb - np.asarray(PICK_COLOR, dtype=float), axis=1) < 70).sum())


def test_a_skeletal_points_smoothness_support_shows_its_neighbours_tangents(window, qtbot):
    """On a straight cylinder's axis every tangent is the axis: s = 1, angles 0; the engine's value
    is reproduced by the support's independent computation."""
    cyl = shapes.cylinder(2000, radius=0.5, length=4.0, capped=False, seed=1)
    ev = evaluate(cyl.cloud, cyl.skeletal)
    w = window
    w.session.show_arrays(cyl.cloud, cyl.skeletal, None, ev)
    w.scene.set_metric("smoothness")
    i = int(np.argmin(np.abs(cyl.skeletal[:, 2] - 2.0)))
    w.pick_element(w.scene.element_info("skeletal", "points", i))
    sup = w.supports.support
    assert sup.kind == "smoothness"
    assert sup.value == pytest.approx(ev.skeletal.smoothness[i], abs=1e-9)
    assert abs(sup.detail.tangent[2]) == pytest.approx(1.0, abs=1e-3)  # along the axis (z)
    assert len(sup.detail.neighbours) >= 1 and np.all(np.abs(sup.detail.neighbour_tangents[:, 2]) > 0.999)
    names = set(w.supports.overlay.names)
    assert {"support-tangent", "support-neighbours", "support-worst", "support-worst_tangent"} <= names
    assert "s = " in w.supports.panel.title


def test_a_curve_vertex_smoothness_support_is_its_edges_angle(window):
    """An L: the corner's two edges meet at 90 degrees, so s = 0 (docs/metrics.md 4); a vertex of degree 1 has none."""
    verts = np.array([[0.0, 0, 0], [1, 0, 0], [1, 1, 0]])
    curve = CurveSkeleton.from_raw(verts, np.array([[0, 1], [1, 2]]))
    pts = np.vstack([np.linspace(verts[0], verts[1], 200), np.linspace(verts[1], verts[2], 200)])
    cloud = pts + np.random.default_rng(0).normal(scale=0.05, size=pts.shape)
    ev = evaluate(cloud, curve=curve)
    w = window
    w.session.show_arrays(cloud, None, curve, ev)
    w.scene.set_metric("smoothness")
    w.pick_element(w.scene.element_info("curve", "vertices", 1))
    sup = w.supports.support
    assert sup.kind == "smoothness" and sup.value == pytest.approx(0.0, abs=1e-12)
    assert np.degrees(sup.detail.theta) == pytest.approx(90.0)
    assert sup.value == pytest.approx(ev.curve.vertex_smoothness[1], abs=1e-12)
    assert "support-edges" in w.supports.overlay.names
    w.pick_element(w.scene.element_info("curve", "vertices", 0))
    assert w.supports.support.kind == "smoothness" and "degree 1" in w.supports.support.reason


def test_support_colours_stand_apart_from_the_skeleton_and_every_overlay_has_a_legend_entry(window, y_eval):
    from skelcore.colors import CLOUD_GREY, CURVE_COLOR, MAGENTA, PICK_COLOR, SKELETAL_COLOR, SUPPORT_COLORS, lookup_table

    fixed = np.array([CURVE_COLOR, SKELETAL_COLOR, MAGENTA, PICK_COLOR, CLOUD_GREY], dtype=float)
    viridis = lookup_table("viridis", 256).astype(float)
    for name, colour in SUPPORT_COLORS.items():
        c = np.asarray(colour, dtype=float)
        assert np.linalg.norm(fixed - c, axis=1).min() > 60, name  # e.g. a red slab against the red curve
        assert np.linalg.norm(viridis - c, axis=1).min() > 45, name
    sh, curve, ev = y_eval
    w = window
    w.session.show_arrays(sh.cloud, sh.skeletal, curve, ev)
    for metric, info in (("centeredness", w.scene.element_info("curve", "samples", 40)),
                         ("centeredness", w.scene.element_info("skeletal", "points", 7)),
                         ("smoothness", w.scene.element_info("skeletal", "points", 7))):
        w.scene.set_metric(metric)
        w.pick_element(info)
        overlay = w.supports.overlay
        labels = [label for label, _ in overlay.legend]
        drawn = [n for n in overlay.names]
        assert len(labels) == len(drawn) + 1 and labels[0] == "picked element"  # + the pick marker
        assert len(set(labels)) == len(labels)
        assert w.view.plotter.legend is not None


def test_the_slab_ellipse_is_drawn_in_3d_on_the_cross_section(window):
    cyl = shapes.cylinder(2500, radius=0.5, length=4.0, capped=False, seed=4)
    curve = CurveSkeleton.from_raw(cyl.curve_vertices, cyl.curve_edges)
    ev = evaluate(cyl.cloud, cyl.skeletal, curve)
    w = window
    w.session.show_arrays(cyl.cloud, cyl.skeletal, curve, ev)
    w.scene.set_metric("centeredness")
    i = int(np.argmin(np.abs(ev.curve.samples[:, 2] - 2.0)))
    w.pick_element(w.scene.element_info("curve", "samples", i))
    ring = w.supports.support.lines3d["ellipse"]
    assert "support-ellipse" in w.supports.overlay.names
    np.testing.assert_allclose(np.hypot(ring[:, 0], ring[:, 1]), 0.5, atol=0.02)  # the cylinder's circle
    np.testing.assert_allclose(ring[:, 2], ev.curve.samples[i, 2], atol=1e-9)  # in the sample's plane


def test_the_slab_plots_legend_sits_beside_its_data(window, qtbot):
    cyl = shapes.cylinder(2500, radius=0.5, length=4.0, capped=False, seed=4)
    curve = CurveSkeleton.from_raw(cyl.curve_vertices, cyl.curve_edges)
    ev = evaluate(cyl.cloud, cyl.skeletal, curve)
    w = window
    w.session.show_arrays(cyl.cloud, cyl.skeletal, curve, ev)
    w.scene.set_metric("centeredness")
    w.pick_element(w.scene.element_info("curve", "samples", 30))
    panel = w.supports.panel
    fig = panel.figure
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    ax = fig.axes[0]
    box = ax.get_legend().get_window_extent(renderer)
    for coll in ax.collections:
        xy = coll.get_offset_transform().transform(coll.get_offsets())
        inside = (xy[:, 0] >= box.x0) & (xy[:, 0] <= box.x1) & (xy[:, 1] >= box.y0) & (xy[:, 1] <= box.y1)
        assert not inside.any()
    assert box.x0 >= ax.get_window_extent(renderer).x1  # beside the axes, not on them


def test_a_setting_change_greys_the_3d_colours_and_the_histogram(window, qtbot, y_eval):
    from skelscope.view.style import greyed, make_lut

    sh, curve, ev = y_eval
    w = window
    w.session.show_arrays(sh.cloud, sh.skeletal, curve, ev)
    w.docks["Histogram"].raise_()
    qtbot.waitUntil(lambda: w.histogram.axes() is not None and bool(w.histogram.axes().patches), timeout=20000)
    lut = w.view._actors["skeletal"].mapper.lookup_table
    fresh = np.asarray(lut.values)[:, :3].copy()
    w.settings_panel.smooth_k.setValue(w.settings_panel.smooth_k.value() + 3)
    assert w.summary.stale == "settings changed" and w.scene.stale == "settings changed"
    lut = w.view._actors["skeletal"].mapper.lookup_table
    now = np.asarray(lut.values)[:, :3]
    assert np.array_equal(now, np.array([greyed(tuple(c)) for c in fresh.astype(int)]))
    assert np.all(now.std(axis=1) < fresh.std(axis=1) + 1e-9)  # less saturated everywhere
    qtbot.waitUntil(lambda: w.histogram.stale == "settings changed", timeout=20000)
    ax = w.histogram.axes()
    qtbot.waitUntil(lambda: any("re-run" in t.get_text() for t in ax.texts), timeout=20000)
    from matplotlib.colors import to_rgb

    assert all(np.ptp(to_rgb(p.get_facecolor())) < 0.01 for p in ax.patches)  # grey bars
    # back to the evaluated settings: the colours come back
    w.settings_panel.smooth_k.setValue(w.settings_panel.smooth_k.value() - 3)
    assert w.scene.stale == ""
    assert np.array_equal(np.asarray(w.view._actors["skeletal"].mapper.lookup_table.values)[:, :3],
                          np.asarray(make_lut((0.0, 1.0)).values)[:, :3])


def test_closing_the_curve_keeps_the_skeletal_sets_results(window, qtbot, y_eval):
    sh, curve, ev = y_eval
    w = window
    w.session.show_arrays(sh.cloud, sh.skeletal, curve, ev)
    cells = {row: w.summary.cell_text(row, "skeletal points") for row in ("d_B / d_Wp", "boundedness", "centeredness")}
    w.session.close_layer("curve")
    kept = w.scene.evaluation
    assert kept is not None and kept.curve is None and kept.skeletal is ev.skeletal and kept.topology is ev.topology
    assert {row: w.summary.cell_text(row, "skeletal points") for row in cells} == cells
    assert w.summary.cell_text("boundedness", "curve skeleton") == "—"
    assert w.summary.stale == "" and not w.summary.is_greyed()
    assert w.scene.skeletal.quantity("boundedness") is not None
    assert w.view._coloured.get("skeletal")  # still coloured by its metric
    w.session.close_layer("skeletal")  # nothing left to score
    assert w.scene.evaluation is None
