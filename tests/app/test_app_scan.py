"""Real scans in the viewer: the openings of a partial scan drawn as their boundary loops, stray points
drawn in a style of their own (both with a legend entry and a Defects row), and the viewpoint set from
the camera or typed, used by the next evaluation (viewpoint-aware boundedness)."""

from __future__ import annotations

import copy

import numpy as np
import pytest
from scipy.spatial import cKDTree

from skelcore import evaluate, shapes
from skelcore.colors import DEFECT_COLORS
from skelcore.curve import CurveSkeleton
from skelcore.io import load_cloud

pytestmark = [pytest.mark.gui, pytest.mark.window(size=(1300, 850), dialogs="record")]


def _half_cylinder():
    """The cylinder's front half (y > 0), as one sensor on the +y side sees it, with its true axis."""
    s = shapes.cylinder(n=4000, seed=1)
    return s.cloud[s.cloud[:, 1] > 0], CurveSkeleton.from_raw(s.curve_vertices, s.curve_edges)


@pytest.fixture(scope="module")
def half_evaluated():
    """The front half, its axis and its evaluation (the curve alone, the engine's defaults), evaluated once
    for the two tests that read it: the frame fit tried on its mostly unbounded axis is most of the
    evaluation's 2-3 CPU s. The window is given a copy, so a test's window never changes another's."""
    cloud, curve = _half_cylinder()
    return cloud, curve, evaluate(cloud, curve=curve)


def _has_colour(img, rgb, tol=12, at_least=5):
    d = np.abs(img[..., :3].astype(int) - np.asarray(rgb)[None, None, :]).max(axis=2)
    return int(np.count_nonzero(d <= tol)) >= at_least


def _spacing(cloud):
    return float(np.median(cKDTree(cloud).query(cloud, k=2)[0][:, 1]))


def _drawn_segments(w):
    """The drawn openings' points and the lengths of their segments."""
    mesh = w.view.plotter.actors["defect-open_surface"].GetMapper().GetInput()
    pts = np.asarray(mesh.points, dtype=float)
    lines = np.asarray(mesh.lines).reshape(-1, 3)[:, 1:]
    return pts, np.linalg.norm(pts[lines[:, 0]] - pts[lines[:, 1]], axis=1)


def test_openings_are_drawn_as_their_boundary_loops(window, half_evaluated):
    cloud, curve, ev = half_evaluated
    ev = copy.deepcopy(ev)
    assert ev.scan.openings and "open_surface" in {w.code for w in ev.warnings}
    w = window
    w.session.show_arrays(cloud, None, curve, ev)
    rows = [r for r in w.defects.rows if r.code == "open_surface"]
    assert len(rows) == len(ev.scan.openings)
    rim = np.concatenate([np.asarray(o["rows"]) for o in ev.scan.openings])
    drawn, lengths = _drawn_segments(w)
    assert len(drawn) >= 0.8 * len(rim)  # the rim followed along its points (side twigs left out)
    assert cKDTree(cloud[rim]).query(drawn)[0].max() < 1e-4
    assert lengths.max() <= 5 * _spacing(cloud)
    assert "opening (boundary loop)" in w.defects.overlay.legend_labels
    assert _has_colour(w.view.image(), DEFECT_COLORS["open_surface"])
    # the rim of a missing side lies on the cut plane y = 0 (the scan's edge)
    assert np.median(np.abs(cloud[rim, 1])) < 0.05


def test_a_one_sided_scan_s_rim_is_drawn_along_the_rim_without_chords(window):
    """The hammer seen from one side (its points with x above the median), with the skeletonizer's curve
    of that half: the opening's rim is a long thin band round the cut; drawn along its points, no
    segment crosses the shape."""
    from pathlib import Path

    from skelcore import skeletonize

    hammer = load_cloud(str(Path(__file__).resolve().parents[2] / "resources" / "scans" / "hammer_4096.ply"))
    half = hammer[hammer[:, 0] > np.median(hammer[:, 0])]
    _skeletal, line = skeletonize(half, method="cao")
    ev = evaluate(half, curve=line)
    assert ev.scan.openings
    w = window
    w.session.show_arrays(half, None, line, ev)
    rim = np.concatenate([np.asarray(o["rows"]) for o in ev.scan.openings])
    drawn, lengths = _drawn_segments(w)
    spacing = _spacing(half)
    assert lengths.max() <= 5 * spacing  # an angular sort drew chords over 100 spacings long
    assert len(drawn) >= 0.8 * len(rim) and len(lengths) >= 0.8 * len(drawn)
    assert lengths.sum() >= 0.5 * np.ptp(half, axis=0).max()  # along the whole cut, not a few pieces


def test_stray_points_are_drawn_large_with_a_legend_entry(window):
    s = shapes.cylinder(n=3000, seed=2)
    far = np.array([[40.0, 0.0, 2.0]])  # 10 x the cylinder's extent away
    cloud = np.vstack([s.cloud, far])
    curve = CurveSkeleton.from_raw(s.curve_vertices, s.curve_edges)
    ev = evaluate(cloud, curve=curve)
    w = window
    w.session.show_arrays(cloud, None, curve, ev)
    (row,) = [r for r in w.defects.rows if r.code == "outliers"]
    assert row.cloud_rows.tolist() == [len(s.cloud)] and "stray point" in row.size
    actor = w.view.plotter.actors["defect-outliers"]
    np.testing.assert_allclose(np.asarray(actor.GetMapper().GetInput().points), far, atol=1e-4)
    assert actor.GetProperty().GetPointSize() >= 10 and "stray point (outlier)" in w.defects.overlay.legend_labels
    w.defects.select(w.defects.rows.index(row))  # framed: the stray point in view
    xy = np.array(w.view.world_to_display(far[0])) / w.view.plotter.devicePixelRatioF()
    assert 0 <= xy[0] <= w.view.widget.width() and 0 <= xy[1] <= w.view.widget.height()


def test_the_viewpoint_from_the_camera_or_typed_is_used_by_the_next_evaluation(window, qtbot):
    cloud, curve = _half_cylinder()
    w = window
    w.session.show_arrays(cloud, None, curve)
    w.session.start_evaluation()
    qtbot.waitUntil(lambda: w.scene.evaluation is not None and not w.session.runner.running, timeout=60000)
    paper = w.scene.scores().boundedness_curve
    assert paper < 0.3  # the paper's boundedness: rays leave through the missing back
    w.view.standard_view("xz")  # the camera on the -y side ... then typed: the sensor on +y
    w.actions_by_name["viewpoint_camera"].trigger()
    position = tuple(w.view.camera_state()["position"])
    assert w.session.viewpoints == [pytest.approx(position)]
    assert w.session.stale_reason() == "settings changed"
    assert not w.viewpoints.set_text("0 1") and "three finite numbers" in w.dialogs[-1]
    assert w.viewpoints.set_text("0 5 2")
    w.session.start_evaluation()
    qtbot.waitUntil(lambda: w.scene.evaluation is not None and not w.session.runner.running, timeout=60000)
    assert w.scene.evaluation.scan.viewpoints == [[0.0, 5.0, 2.0]] and w.session.stale_reason() == ""
    assert w.scene.scores().boundedness_curve >= 0.95  # the goal of viewpoint-aware scores, through the window
    w.actions_by_name["viewpoint_clear"].trigger()
    assert w.session.viewpoints == [] and w.session.stale_reason() == "settings changed"


def test_the_scan_warnings_name_the_window_s_remedies_which_then_work(window, qtbot, tmp_path, half_evaluated):
    """The ``outliers`` and ``open_surface`` warnings name the Settings panel's check boxes and the
    viewpoint actions, not command-line flags; ticking "evaluate without stray points" makes the next run
    leave them out (stale until then), and a saved session keeps the boxes."""
    import json

    from skelscope.panels.summary import window_warning

    s = shapes.cylinder(n=3000, seed=2)
    cloud = np.vstack([s.cloud, [[40.0, 0.0, 2.0]]])
    curve = CurveSkeleton.from_raw(s.curve_vertices, s.curve_edges)
    w = window
    w.session.show_arrays(cloud, None, curve)
    w.session.start_evaluation()
    qtbot.waitUntil(lambda: w.scene.evaluation is not None and not w.session.runner.running, timeout=60000)
    (stray,) = [x for x in w.scene.evaluation.warnings if x.code == "outliers"]
    text = window_warning(stray)
    assert "--" not in text and "Settings > stray points > evaluate without stray points" in text
    assert not w.scene.evaluation.scan.outliers_removed
    w.settings_panel.remove_outliers.setChecked(True)
    assert w.session.stale_reason() == "settings changed"
    w.session.start_evaluation()
    qtbot.waitUntil(lambda: w.scene.evaluation is not None and not w.session.runner.running
                    and w.scene.evaluation.scan is not None and w.scene.evaluation.scan.outliers_removed, timeout=60000)
    assert w.session.stale_reason() == ""
    assert w.scene.evaluation.normalization.scale == pytest.approx(evaluate(s.cloud, curve=curve).normalization.scale)
    opened = [x for x in half_evaluated[2].warnings if x.code == "open_surface"]
    assert opened and "--" not in window_warning(opened[0])
    assert "Evaluate > Viewpoint from the camera" in window_warning(opened[0])
    assert "Settings > openings" in window_warning(opened[0])
    from skelcore.io import write_curve_ply, write_points_ply

    write_points_ply(tmp_path / "c.ply", cloud)
    write_curve_ply(tmp_path / "k.ply", s.curve_vertices, s.curve_edges)
    w.session.close_all()
    w.session.load_as("cloud", str(tmp_path / "c.ply"))
    w.session.load_as("curve", str(tmp_path / "k.ply"))
    path = tmp_path / "scan_session.json"
    w.saved_sessions.save(str(path))
    assert json.loads(path.read_text())["scan_options"] == {"remove_outliers": True, "cap_openings": False}
    w.settings_panel.set_scan_options()
    assert w.saved_sessions.open(str(path)) == [] and w.settings_panel.remove_outliers.isChecked()
    w.settings_panel.set_scan_options()
