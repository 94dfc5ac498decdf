"""Supports in the window: a picked element's support plotted and highlighted, on shapes with known
answers (a cylinder's cross-section, a point outside a sphere), and the below-threshold filter."""

from __future__ import annotations

import numpy as np
import pytest
from PySide6 import QtCore

from skelcore import evaluate, shapes
from skelcore.curve import CurveSkeleton

pytestmark = [pytest.mark.gui, pytest.mark.window(size=(1300, 850))]

RADIUS = 0.5


@pytest.fixture(scope="module")
def cylinder_eval():
    cyl = shapes.cylinder(2500, radius=RADIUS, length=4.0, capped=False, seed=4)
    curve = CurveSkeleton.from_raw(cyl.curve_vertices, cyl.curve_edges)
    return cyl, curve, evaluate(cyl.cloud, cyl.skeletal, curve)


@pytest.fixture
def cylinder_window(window, cylinder_eval):
    cyl, curve, ev = cylinder_eval
    window.session.show_arrays(cyl.cloud, cyl.skeletal, curve, ev)
    return window


def _rgb_count(img: np.ndarray, colour) -> int:
    return int(np.all(np.asarray(img)[..., :3].reshape(-1, 3) == np.asarray(colour), axis=1).sum())


def _middle_sample(ev) -> int:
    z = ev.curve.samples[:, 2]
    return int(np.argmin(np.abs(z - 2.0)))


def test_a_curve_samples_plot_shows_a_circular_ring_centred_on_the_axis(cylinder_window, cylinder_eval, qtbot):
    from matplotlib.patches import Ellipse

    w = cylinder_window
    _, _, ev = cylinder_eval
    w.scene.set_metric("centeredness")
    i = _middle_sample(ev)
    w.pick_element(w.scene.element_info("curve", "samples", i))
    assert w.pick.info["index"] == i  # the pick panel still gets the pick
    sup = w.supports.panel.support
    assert sup.kind == "slab" and sup.value == pytest.approx(ev.curve.sample_centeredness_raw[i], abs=1e-12)
    ax = w.supports.panel.figure.axes[0]
    slab, ring = ax.collections[0].get_offsets(), ax.collections[1].get_offsets()
    assert len(ring) > 10 and len(slab) >= len(ring)
    # the plot is in the user's units: the ring kept is the circle of radius 0.5 around the axis
    np.testing.assert_allclose(np.hypot(ring[:, 0], ring[:, 1]), RADIUS, atol=1e-6)
    (ellipse,) = [p for p in ax.patches if isinstance(p, Ellipse)]
    assert ellipse.width / 2 == pytest.approx(RADIUS, abs=0.02)
    assert ellipse.height / 2 == pytest.approx(RADIUS, abs=0.02)
    np.testing.assert_allclose(ellipse.center, 0.0, atol=0.02)
    assert "c = " in w.supports.panel.title
    # 3-D: the slab's cloud points and the ring are highlighted, the centre lies on the axis
    pts = sup.points3d
    half = sup.detail.half_width / ev.normalization.scale
    assert np.all(np.abs(pts["slab"][:, 2] - ev.curve.samples[i, 2]) < half + 1e-9)
    np.testing.assert_allclose(pts["centre"][0, :2], 0.0, atol=0.02)
    assert {"support-slab", "support-ring", "support-centre"} <= set(w.supports.overlay.names)
    w.scene.set_visible("cloud", False)
    from skelscope.view.support_overlay import OVERLAY_COLOURS

    assert _rgb_count(w.view.image(), OVERLAY_COLOURS["ring"][0]) > 20
    # a new result clears the highlight
    w.scene.set_evaluation(ev)
    assert w.supports.overlay.names == [] and w.supports.panel.support is None


def test_a_skeletal_points_neighbours_and_centroids_are_shown(cylinder_window, cylinder_eval):
    w = cylinder_window
    cyl, _, ev = cylinder_eval
    w.scene.set_metric("centeredness")
    w.pick_element(w.scene.element_info("skeletal", "points", 100))
    sup = w.supports.support
    assert sup.kind == "knn"
    assert sup.value == pytest.approx(ev.skeletal.centeredness_raw[100], abs=1e-12)
    nb = sup.points3d["neighbours"]
    # pointwise correspondence: each neighbour's cloud point is the cloud row of the same index
    np.testing.assert_array_equal(sup.points3d["cloud"], cyl.cloud[sup.detail.neighbours])
    np.testing.assert_allclose(sup.points3d["m_s"][0], nb.mean(axis=0), atol=1e-12)
    np.testing.assert_allclose(sup.points3d["m_o"][0], cyl.cloud[sup.detail.neighbours].mean(axis=0), atol=1e-12)
    assert np.all(np.linalg.norm(sup.points3d["cloud"][:, :2], axis=1) == pytest.approx(RADIUS))
    assert {"support-neighbours", "support-cloud", "support-m_s", "support-m_o", "support-links"} <= set(
        w.supports.overlay.names)
    # switching the metric shows that metric's support for the same element
    w.scene.set_metric("boundedness")
    assert w.supports.support.kind == "directions" and w.supports.overlay.names == []
    w.scene.set_metric("smoothness")  # (smoothness has a support too, tests/app/test_app_picking.py)
    assert w.supports.support.kind == "smoothness"


def test_a_point_outside_a_sphere_covers_the_cap_fraction_of_its_direction_map(window):
    radius, dist = 1.0, 2.0
    cloud = shapes.sphere_surface(3000, radius, seed=2)
    skeletal = np.array([[0.0, 0.0, dist], [0.0, 0.0, 0.0], [0.3, 0.0, 0.0]])
    ev = evaluate(cloud, skeletal)
    window.session.show_arrays(cloud, skeletal, None, ev)
    window.scene.set_metric("boundedness")
    window.pick_element(window.scene.element_info("skeletal", "points", 0))
    sup = window.supports.support
    assert sup.kind == "directions"
    h = sup.detail.radius / ev.normalization.scale  # the balls' radius, in the user's units
    cap = (1.0 - np.cos(np.arcsin((radius + h) / dist))) / 2.0
    ax = window.supports.panel.figure.axes[0]
    shown = np.asarray(ax.images[0].get_array())
    assert shown.mean() == pytest.approx(cap, abs=0.02)
    assert shown[0].all() and not shown[-1].any()  # the covered directions point down, at the sphere
    assert shown.mean() == pytest.approx(ev.skeletal.boundedness[0], abs=0.01)
    assert "beta = " in window.supports.panel.title
    # the centre of the sphere sees (nearly) every direction, as the engine says
    window.pick_element(window.scene.element_info("skeletal", "points", 1))
    inside = np.asarray(window.supports.panel.figure.axes[0].images[0].get_array()).mean()
    assert inside > 0.9 and inside == pytest.approx(ev.skeletal.boundedness[1], abs=0.01)


def test_the_filter_shows_only_the_elements_below_the_threshold(cylinder_window, cylinder_eval):
    w = cylinder_window
    _, _, ev = cylinder_eval
    w.scene.set_metric("boundedness")
    w.scene.set_thresholds(0.9, 0.75)
    below = ~(ev.skeletal.boundedness > 0.9)
    assert 0 < below.sum() < len(below)
    box = w.supports.filter_box
    assert box.isEnabled()
    box.setChecked(True)
    view = w.view
    assert not view._actors["skeletal"].GetVisibility()
    assert "filter-skeletal" in view.plotter.renderer.actors
    mesh = w.supports.filter_meshes["filter-skeletal"]
    assert mesh.n_points == int(below.sum())
    np.testing.assert_allclose(mesh["values"], ev.skeletal.boundedness[below])
    assert w.supports.filtered_counts()["skeletal"] == (int(below.sum()), len(below))
    # a hidden element cannot be picked: a click on it finds a shown one or nothing
    w.scene.set_visible("curve", False)
    view.image()
    for j in np.flatnonzero(~below)[:5]:
        info = view.pick_display(*view.world_to_display(w.scene.skeletal.points[j]))
        assert info is None or not info["values"]["boundedness"] > 0.9
    w.scene.set_visible("curve", True)
    # a new threshold re-filters at once
    w.scene.set_thresholds(0.95, 0.75)
    assert w.supports.filter_meshes["filter-skeletal"].n_points == int((~(ev.skeletal.boundedness > 0.95)).sum())
    # the curve samples are filtered too (boundedness lives on them)
    assert w.supports.filter_meshes["filter-curve-samples"].n_points == int((~(ev.curve.sample_boundedness > 0.95)).sum())
    # smoothness has no threshold: the box is disabled and everything shows again
    w.scene.set_metric("smoothness")
    assert not box.isEnabled() and view._actors["skeletal"].GetVisibility()
    box.setChecked(False)
    w.scene.set_metric("boundedness")
    assert view._actors["skeletal"].GetVisibility() and "filter-skeletal" not in view.plotter.renderer.actors


@pytest.fixture(scope="module")
def b_eval(cylinder_eval):
    cyl, curve, _ = cylinder_eval
    shifted = cyl.skeletal + np.array([0.15, 0.0, 0.0])  # an off-centre skeleton B of the same cloud
    return shifted, evaluate(cyl.cloud, shifted, curve)


def test_the_ab_table_shows_both_evaluations_and_their_differences(cylinder_window, cylinder_eval, b_eval):
    from skelscope.compare_view import ab_rows

    w = cylinder_window
    _, _, ev_a = cylinder_eval
    _, ev_b = b_eval
    view = w.compare.open(ev_a, ev_b, ("A", "shifted"))
    try:
        sa, sb = ev_a.summary(), ev_b.summary()
        expected = {
            "d_B": (sa["topology"]["bottleneck"], sb["topology"]["bottleneck"]),
            "centeredness (skeletal)": (sa["centeredness"]["skeletal"], sb["centeredness"]["skeletal"]),
            "boundedness (curve)": (sa["boundedness"]["curve"], sb["boundedness"]["curve"]),
        }
        rows = {label: (a, b, d) for label, a, b, d in view.rows}
        for label, (a, b) in expected.items():
            assert rows[label] == (a, b, b - a)
        assert rows["centeredness (skeletal)"][2] < 0  # the shifted skeleton is less centred
        assert [r[0] for r in view.rows] == [r[0] for r in ab_rows(sa, sb)]
        for r, (label, a, b, d) in enumerate(view.rows):
            assert view.cell(r, 0) == label
            assert float(view.cell(r, 3)) == pytest.approx(d, abs=5e-5)
            assert float(view.cell(r, 3)) == pytest.approx(float(view.cell(r, 2)) - float(view.cell(r, 1)), abs=2e-4)
        # linked cameras: both halves look through one camera
        cams = [ren.GetActiveCamera() for ren in view.plotter.renderers]
        assert len(cams) == 2 and cams[0] is cams[1]
        # both halves drawn: each renderer has the cloud, the skeletal points and the curve
        assert all(len(ren.actors) >= 3 for ren in view.plotter.renderers)
        view.metric_box.setCurrentText("boundedness")  # redrawn by the other metric, in both halves
        assert all(len(ren.actors) >= 3 for ren in view.plotter.renderers)
        assert list(view.plotter.scalar_bars.keys()) == ["boundedness"]
        img = view.image()
        half = img.shape[1] // 2
        assert (img[:, :half, :3] < 200).any() and (img[:, half:, :3] < 200).any()
    finally:
        view.close()


def test_skeleton_b_is_evaluated_in_the_worker_and_opens_the_ab_view(cylinder_window, cylinder_eval, b_eval, qtbot):
    w = cylinder_window
    _, _, ev_a = cylinder_eval
    shifted, ev_b = b_eval
    assert w.compare.compare_arrays(shifted, None, "shifted")
    qtbot.waitUntil(lambda: bool(w.compare.views), timeout=120000)
    view = w.compare.views[-1]
    try:
        rows = {label: (a, b, d) for label, a, b, d in view.rows}
        assert rows["centeredness (skeletal)"][1] == pytest.approx(ev_b.summary()["centeredness"]["skeletal"])
        assert rows["centeredness (skeletal)"][0] == ev_a.summary()["centeredness"]["skeletal"]
        assert np.isnan(rows["boundedness (curve)"][1])  # B has no curve: no score, no difference
        assert view.cell(list(rows).index("boundedness (curve)"), 3) == "—"
        w.close()  # the A/B window closes with the main window
        assert not view.isVisible() and w.compare.views == []
    finally:
        view.close()


def test_a_big_clouds_support_is_computed_in_a_thread_and_the_newest_pick_wins(cylinder_window, cylinder_eval, qtbot):
    w = cylinder_window
    _, _, ev = cylinder_eval
    w.supports.background_points = 0  # every cloud counts as big
    w.scene.set_metric("boundedness")
    w.pick_element(w.scene.element_info("skeletal", "points", 5))
    assert w.supports.show_element(w.scene.element_info("skeletal", "points", 7)) is None  # not computed here
    assert "computing" in w.supports.panel.support.reason
    qtbot.waitUntil(lambda: not w.supports.busy, timeout=60000)
    sup = w.supports.support
    assert sup.kind == "directions" and sup.index == 7
    assert sup.detail.fraction == pytest.approx(ev.skeletal.boundedness[7], abs=0.01)


def _slow_first_support(monkeypatch, slow_index: int) -> dict:
    """Make the support of skeletal point ``slow_index`` a 30 s computation in small Python steps (one
    sharing the interpreter with every other until it ends); the others are computed as usual."""
    import time

    import skelscope.support_controller as controller

    real = controller.element_support
    state = {"started": False, "finished": False}

    def support(ev, info, metric, checkpoint=None):
        if info is not None and info["index"] == slow_index:
            state["started"] = True
            end = time.monotonic() + 30.0
            while time.monotonic() < end:
                sum(i * i for i in range(2000))  # busy, holding the interpreter between steps
            state["finished"] = True
        return real(ev, info, metric, checkpoint)

    monkeypatch.setattr(controller, "element_support", support)
    return state


def _support_threads() -> list:
    import threading

    return [t for t in threading.enumerate() if t.name == "skelscope-support" and t.is_alive()]


def test_a_new_pick_stops_the_support_still_computing(cylinder_window, qtbot, monkeypatch):
    w = cylinder_window
    w.supports.background_points = 0  # every cloud counts as big: supports in a thread
    w.scene.set_metric("boundedness")
    state = _slow_first_support(monkeypatch, 5)
    assert w.supports.show_element(w.scene.element_info("skeletal", "points", 5)) is None
    qtbot.waitUntil(lambda: state["started"], timeout=5000)
    w.supports.show_element(w.scene.element_info("skeletal", "points", 7))
    qtbot.waitUntil(lambda: not w.supports.busy, timeout=10000)
    assert not state["finished"]  # shown before the first one's 30 s were over
    assert w.supports.support.index == 7 and w.supports.support.kind == "directions"
    qtbot.waitUntil(lambda: not _support_threads(), timeout=3000)  # the first computation stopped
    assert not state["finished"]


def test_quitting_stops_the_support_still_computing(cylinder_window, qtbot, monkeypatch):
    w = cylinder_window
    w.supports.background_points = 0
    w.scene.set_metric("boundedness")
    state = _slow_first_support(monkeypatch, 5)
    w.supports.show_element(w.scene.element_info("skeletal", "points", 5))
    qtbot.waitUntil(lambda: state["started"], timeout=5000)
    w.close()
    assert not state["finished"]  # closed without waiting out the first one's 30 s
    qtbot.waitUntil(lambda: not _support_threads(), timeout=3000)
    assert not state["finished"]


def test_a_real_click_on_a_curve_sample_fills_the_support_dock(cylinder_window, cylinder_eval, qtbot):
    w = cylinder_window
    _, _, ev = cylinder_eval
    w.scene.set_metric("centeredness")
    for name in ("cloud", "skeletal"):
        w.scene.set_visible(name, False)
    w.view.standard_view("xz")
    w.view.image()
    i = int(np.argmin(np.abs(ev.curve.samples[:, 2] - 2.1)))  # halfway between two curve vertices
    x, y = w.view.world_to_display(ev.curve.samples[i])
    widget = w.view.widget
    ratio = widget.devicePixelRatioF()
    pos = QtCore.QPoint(int(round(x / ratio)), int(round(widget.height() - y / ratio)))
    qtbot.mouseClick(widget, QtCore.Qt.MouseButton.LeftButton, pos=pos)
    sup = w.supports.support
    assert w.pick.info is not None and w.pick.info["element"] == "curve sample"
    assert sup.kind == "slab" and abs(sup.points3d["query"][0, 2] - ev.curve.samples[i, 2]) < 0.05
    assert w.supports.panel.title.startswith(f"curve sample #{sup.index}")
