"""Defects on screen: the Defects dock lists each defect found with its size, selecting one
frames the camera on it and highlights it; in 3-D, missing parts colour their cloud points, flagged
branches and outside edges are drawn in styles of their own with a legend entry each; a switch hides
them; a click on the curve selects its branch (length, radius, metric means, flags).

The skeleton: a capped cylinder's axis with its lower 40 % cut (a missing part, below z = 1.6) and a
straight spur from the axis out to 2 units sideways (radius 0.5: spurious and 1.5 of its 2 units
outside the shape), so every answer is known."""

from __future__ import annotations

import numpy as np
import pytest

from skelcore import evaluate, shapes
from skelcore.colors import DEFECT_COLORS, PICK_COLOR
from skelcore.curve import CurveSkeleton

pytestmark = [pytest.mark.gui, pytest.mark.window(size=(1300, 850))]
CUT_Z = 1.6


def spurred_cut_cylinder():
    s = shapes.cylinder(n=3000, seed=2)
    axis = s.curve_vertices[8:]  # z from 1.6 to 4
    z = axis[5, 2]
    v = np.vstack([axis, [[0.7, 0, z], [1.4, 0, z], [2.0, 0, z]]])
    n = len(v)
    e = np.vstack([np.column_stack([np.arange(len(axis) - 1), np.arange(1, len(axis))]),
                   [[5, n - 3], [n - 3, n - 2], [n - 2, n - 1]]])
    return s, CurveSkeleton.from_raw(v, e), {n - 3, n - 2, n - 1}


@pytest.fixture(scope="module")
def defective():
    s, curve, spur = spurred_cut_cylinder()
    return s, curve, spur, evaluate(s.cloud, curve=curve)


def _show(w, s, curve, ev):
    w.session.show_arrays(s.cloud, None, curve, ev)
    w.view.image()  # a frame at the final size: the camera is set
    return w


def _spur_edges(curve, spur):
    e = np.asarray(curve.edges)
    return set(np.flatnonzero(np.isin(e, list(spur)).any(axis=1)).tolist())


def _has_colour(img, rgb, tol=12, at_least=5):
    d = np.abs(img[..., :3].astype(int) - np.asarray(rgb)[None, None, :]).max(axis=2)
    return int(np.count_nonzero(d <= tol)) >= at_least


def test_the_dock_lists_each_defect_with_its_size(window, defective):
    s, curve, spur, ev = defective
    w = _show(window, s, curve, ev)
    panel = w.defects.panel
    assert "Defects" in w.docks
    view_menu = next(a.menu() for a in w.menuBar().actions() if a.text() == "&View")
    assert w.docks["Defects"].toggleViewAction() in view_menu.actions()
    codes = [r.code for r in panel.rows]
    assert codes == ["incomplete", "spurious_branches", "outside"]
    assert panel.table.rowCount() == 3
    missing, spur_row, outside = panel.rows
    # the missing part: the cloud below the cut, in the engine's words (share, points, depth)
    z = s.cloud[missing.cloud_rows, 2]
    assert np.mean(z < CUT_Z) > 0.95 and len(missing.cloud_rows) > 0.2 * np.count_nonzero(s.cloud[:, 2] < CUT_Z)
    assert f"{len(missing.cloud_rows)} points" in missing.size and "% of the cloud" in missing.size
    # the spur: its three edges, and 1.5 of its 2 units outside (radius 0.5), as the engine measures it
    assert set(spur_row.edges.tolist()) == _spur_edges(curve, spur)
    assert set(outside.edges.tolist()) <= _spur_edges(curve, spur) and len(outside.edges) >= 2
    length = float(outside.size.split(" long outside")[0])
    assert length == pytest.approx(1.5, abs=0.15)
    assert "not sound" in panel.status.text() and "incomplete" in panel.status.text()
    assert panel.table.item(1, 1).text() == spur_row.size


def test_selecting_a_row_frames_and_highlights_it(window, defective):
    s, curve, spur, ev = defective
    w = _show(window, s, curve, ev)
    width, height = w.view.widget.width(), w.view.widget.height()
    for index in (1, 0):
        w.defects.panel.select_row(index)
        row = w.defects.rows[index]
        assert w.defects.selected is row
        img = w.view.image()
        ratio = w.view.plotter.devicePixelRatioF()
        xy = np.array([w.view.world_to_display(p) for p in row.points]) / ratio
        assert (xy >= 0).all() and (xy[:, 0] <= width).all() and (xy[:, 1] <= height).all()
        extent = np.ptp(xy, axis=0)
        assert max(extent[0] / width, extent[1] / height) > 0.25  # framed: it fills the view
        assert "defect-selected" in w.view.plotter.actors
        assert _has_colour(img, PICK_COLOR)
    w.defects.panel.select_row(-1)
    assert w.defects.selected is None and "defect-selected" not in w.view.plotter.actors


def test_defects_are_drawn_in_styles_of_their_own_with_a_legend_and_can_be_hidden(window, defective):
    s, curve, spur, ev = defective
    w = _show(window, s, curve, ev)
    actors = w.view.plotter.actors
    missing = w.defects.rows[0]
    assert actors["defect-incomplete"].GetMapper().GetInput().GetNumberOfPoints() == len(missing.cloud_rows)
    halo, dashes = actors["defect-spurious_branches"], actors["defect-outside"]
    curve_width = actors["curve-edges"].GetProperty().GetLineWidth()
    assert halo.GetProperty().GetLineWidth() > 3 * curve_width  # a halo, not a recoloured edge
    assert dashes.GetMapper().GetInput().GetNumberOfCells() > len(w.defects.rows[2].edges)  # cut into dashes
    assert w.defects.overlay.legend_labels == ["missing part (cloud points)", "spurious branch",
                                               "edge outside the shape"]
    img = w.view.image()
    assert _has_colour(img, DEFECT_COLORS["incomplete"])
    w.actions_by_name["show_defects"].trigger()  # View > Show defects (Shift+D) off
    assert not w.defects.visible and not w.defects.panel.show_box.isChecked()
    assert not actors["defect-incomplete"].GetVisibility() and not w.defects.overlay.legend.GetVisibility()
    assert not _has_colour(w.view.image(), DEFECT_COLORS["incomplete"])
    w.defects.panel.show_box.setChecked(True)
    assert w.defects.visible and w.actions_by_name["show_defects"].isChecked()
    assert actors["defect-incomplete"].GetVisibility()


def test_a_click_on_the_curve_selects_its_branch(window, qtbot, defective):
    s, curve, spur, ev = defective
    w = _show(window, s, curve, ev)
    w.scene.set_visible("cloud", False)
    w.view.image()
    tip = curve.vertices[max(spur)]
    x, y = w.view.world_to_display(tip)
    info = w.view.pick_display(x, y)
    w.pick_element(info)
    b = info["branch"]
    assert b["flags"] == ["spurious_branches", "outside"]
    assert b["length"] == pytest.approx(2.0, rel=1e-6)  # from the axis out to x = 2
    edges = sorted(_spur_edges(curve, spur))
    on = np.isin(ev.curve.sample_edge, edges)
    assert b["means"]["boundedness"] == pytest.approx(np.nanmean(ev.curve.sample_boundedness[on]), abs=0.02)
    assert b["radius"]["median"] > 0
    text = w.pick.text.toPlainText()
    assert f"branch #{b['branch']}" in text and "spurious_branches, outside" in text and "length 2" in text
    assert set(w.defects.selected.edges.tolist()) == set(edges)
    assert "defect-selected" in w.view.plotter.actors
    # an axis vertex: a branch with no flag
    x, y = w.view.world_to_display(curve.vertices[1])
    info = w.view.pick_display(x, y)
    assert info["branch"]["flags"] == [] and info["branch"]["means"]["boundedness"] > 0.9


def test_a_sound_skeleton_has_none(window):
    sh = shapes.y_shape(1500, seed=3)
    curve = CurveSkeleton.from_raw(sh.curve_vertices, sh.curve_edges)
    ev = evaluate(sh.cloud, sh.skeletal, curve)
    w = _show(window, sh, curve, ev)
    assert w.defects.rows == [] and "none found" in w.defects.panel.status.text()
    assert not [n for n in w.view.plotter.actors if n.startswith("defect-")]
    assert w.defects.overlay.legend is None


def test_the_ab_view_counts_the_defects_of_a_and_b(window, defective):
    """A: the defective skeleton; B: the cylinder's whole axis (sound). The table gets one row per code
    found in either (A's count, B's, B - A, fewer is better) and the sound / not line; each side draws
    its defects."""
    s, curve, spur, ev_a = defective
    w = _show(window, s, curve, ev_a)
    truth = CurveSkeleton.from_raw(s.curve_vertices, s.curve_edges)
    ev_b = evaluate(s.cloud, curve=truth)
    view = w.compare.open(ev_a, ev_b, ("defective", "axis"))
    labels = [view.cell(r, 0) for r in range(view.table.rowCount())]
    n = len(view.rows)
    assert labels[n:] == ["defects: incomplete", "defects: spurious_branches", "defects: outside",
                          "sound (no defect warning)"]
    for r in range(n, n + 3):
        assert (view.cell(r, 1), view.cell(r, 2), view.cell(r, 3)) == ("1", "0", "-1")
        assert view.table.item(r, 3).toolTip() == "B is better"
    last = n + 3
    assert view.cell(last, 1) == "not sound: incomplete, outside, spurious_branches" and view.cell(last, 2) == "sound"
    pink = [a for a in view.plotter.renderers[0].actors.values() if hasattr(a, "prop")  # not the legend
            and tuple(round(c * 255) for c in a.prop.color.float_rgb) == DEFECT_COLORS["incomplete"]]
    assert len(pink) == 1
    assert not [a for a in view.plotter.renderers[1].actors.values() if hasattr(a, "prop")
                and tuple(round(c * 255) for c in a.prop.color.float_rgb) == DEFECT_COLORS["incomplete"]]
    view.close()


def test_out_of_date_results_grey_their_defects_and_keep_the_selection(window, defective):
    """The stale state: a setting change greys the defects as it greys the metric colours."""
    from skelscope.view.style import greyed

    s, curve, spur, ev = defective
    w = _show(window, s, curve, ev)
    w.defects.panel.select_row(1)
    w.scene.set_stale("settings changed")
    img = w.view.image()
    assert not _has_colour(img, DEFECT_COLORS["incomplete"], tol=4) and _has_colour(img, greyed(DEFECT_COLORS["incomplete"]))
    assert "defect-selected" in w.view.plotter.actors and w.defects.selected is w.defects.rows[1]
    w.scene.set_stale("")
    assert _has_colour(w.view.image(), DEFECT_COLORS["incomplete"])


def test_the_ab_view_greys_vacuous_scores_shows_coverage_and_the_defect_legend(window, defective):
    """B is broken: a one-edge curve (no degree-2 vertex: its smoothness is 1 by definition) and a
    skeletal set collapsed to a point (it scores well for nothing). Its vacuous scores are marked and
    their differences grey, never green; coverage, which tells, is compared; each half draws the
    defect legend of the main view."""
    from PySide6 import QtCore

    from skelscope.view.defect_overlay import LEGEND_LABELS

    s, curve, spur, _ = defective
    rng = np.random.default_rng(0)
    bent = CurveSkeleton.from_raw(np.asarray(curve.vertices) + rng.normal(scale=0.03, size=np.shape(curve.vertices)),
                                  curve.edges)  # A's smoothness under 1
    ev_a = evaluate(s.cloud, curve=bent)
    w = _show(window, s, bent, ev_a)
    assert w.defects.overlay.legend is not None  # the main window has a defect legend
    collapsed = s.cloud.mean(axis=0) + rng.normal(scale=1e-3, size=s.cloud.shape)
    ends = s.curve_vertices[[0, -1]]
    one_edge = CurveSkeleton.from_raw(ends, np.array([[0, 1]]))
    ev_b = evaluate(s.cloud, collapsed, one_edge)
    codes = {x.code for x in ev_b.warnings}
    assert {"trivial_smoothness", "collapse"} <= codes
    view = w.compare.open(ev_a, ev_b, ("defective", "broken"))
    try:
        labels = [view.cell(r, 0) for r in range(view.table.rowCount())]
        rows = {label: (a, b, d) for label, a, b, d in view.rows}
        green = QtCore.Qt.GlobalColor.darkGreen
        for label in ("smoothness (curve)", "smoothness (skeletal)", "boundedness (skeletal)"):
            r = labels.index(label)
            assert view.cell(r, 2).endswith("(vacuous)") and "[" in view.table.item(r, 2).toolTip()
        assert view.cell(labels.index("smoothness (skeletal)"), 3) == "—"  # A has no skeletal set
        r = labels.index("smoothness (curve)")
        assert rows["smoothness (curve)"][1] == 1.0 and rows["smoothness (curve)"][2] > 0  # was painted green
        d_item = view.table.item(r, 3)
        assert d_item.foreground().color() == view.palette().color(
            view.palette().ColorGroup.Disabled, view.palette().ColorRole.Text)
        assert "says nothing" in d_item.toolTip() and "trivial_smoothness" in d_item.toolTip()
        assert "collapse" in view.table.item(labels.index("smoothness (skeletal)"), 2).toolTip()
        # coverage, as in the main summary (marked as SkelScope's own), compared and coloured
        summary_rows = [w.summary.table.verticalHeaderItem(i).text() for i in range(w.summary.table.rowCount())]
        assert "coverage*" in summary_rows
        r = labels.index("coverage (curve)*")
        a, b, d = rows["coverage (curve)*"]
        assert b > a and view.table.item(r, 3).foreground().color() == green  # the whole axis covers the cut
        assert "not the paper's" in view.table.item(r, 0).toolTip()
        assert view.cell(labels.index("coverage (skeletal)*"), 2) != "—"  # the collapsed set's, which tells
        # the defect legend in each half that draws defects, in the main view's words
        assert view.legend_labels(0) == [LEGEND_LABELS[k] for k in ("incomplete", "spurious_branches", "outside")]
        view.metric_box.setCurrentText("boundedness")  # redrawn: one legend per half still
        assert view.legend_labels(0) == [LEGEND_LABELS[k] for k in ("incomplete", "spurious_branches", "outside")]
        assert len(view._legends) == 1 + bool(view.legend_labels(1))
        # each legend is kept fitted to its half (text sized at the screen's DPI), one observer per legend
        for renderer, legend, observer in view._legends:
            assert renderer.HasObserver("StartEvent") and observer
            assert legend.GetPosition2()[0] < 0.5  # fitted to its text, not a fixed share of the view
        renderer = view._legends[0][0]
        view.metric_box.setCurrentText("centeredness")  # redrawn: the old legends' observers removed
        tags = [o for r, _legend, o in view._legends if r is renderer]
        assert len(tags) == 1
        assert renderer.GetCommand(tags[0]) is not None
    finally:
        view.close()


def test_the_ab_window_fits_the_screen(window, defective):
    """The A/B window gets the room the screen has (the test's screen is smaller than its usual
    1400 x 850), as the main window does; on a 1366 x 768 laptop it fits too."""
    from PySide6 import QtCore

    from skelscope.compare_view import AB_SIZE

    s, curve, spur, ev = defective
    w = _show(window, s, curve, ev)
    view = w.compare.open(ev, ev, ("A", "same"))
    try:
        free = view.screen().availableGeometry()
        assert free.width() < AB_SIZE[0] or free.height() < AB_SIZE[1]  # a real small-screen check
        assert free.contains(view.frameGeometry()), (view.frameGeometry(), free)

        class Laptop:
            def availableGeometry(self):
                return QtCore.QRect(0, 27, 1366, 741)  # 768 less a top panel

        view.fit_to_screen(Laptop())
        assert Laptop().availableGeometry().contains(QtCore.QRect(view.pos(), view.size()))
    finally:
        view.close()


def test_a_broken_curve_lists_each_extra_piece_and_draws_it_with_a_halo(window):
    """``disconnected`` (docs/diagnostics.md "Disconnected"): one Defects row per extra piece of the
    curve, its branches and edges, drawn as a halo in its own colour with a legend entry."""
    from pathlib import Path

    import skelcore
    from skelcore.diagnostics.pieces import curve_pieces

    samples = Path(__file__).resolve().parents[2] / "resources" / "samples"
    cloud, curve = skelcore.load_cloud(samples / "yshape_cloud.ply"), skelcore.load_curve(samples / "yshape_curve.ply")
    e = np.sort(np.asarray(curve.edges), axis=1)
    keep = ~((e == [3, 4]).all(axis=1) | (e == [14, 15]).all(axis=1))
    broken = CurveSkeleton.from_raw(curve.vertices, np.asarray(curve.edges)[keep])
    ev = evaluate(cloud, curve=broken)
    assert "disconnected" in {x.code for x in ev.warnings}
    w = window
    w.session.show_arrays(cloud, None, broken, ev)
    w.view.image()
    rows = [r for r in w.defects.rows if r.code == "disconnected"]
    assert [r.title for r in rows] == ["broken curve: piece 1 of 2 apart", "broken curve: piece 2 of 2 apart"]
    _n, piece = curve_pieces(broken)
    edges = np.asarray(broken.edges)
    main = np.argmax(np.bincount(piece[edges[:, 0]], weights=broken.edge_lengths()))
    pieces = [set(piece[edges[r.edges, 0]].tolist()) for r in rows]
    assert all(len(p) == 1 for p in pieces) and {p.pop() for p in pieces} == set(range(3)) - {main}
    assert all(len(r.points) and "of the curve's length" in r.size and "nan" not in r.size for r in rows)
    halo = w.view.plotter.actors["defect-disconnected"]
    assert halo.GetMapper().GetInput().GetNumberOfCells() == sum(len(r.edges) for r in rows)
    assert "broken curve (extra piece)" in w.defects.overlay.legend_labels
    assert _has_colour(w.view.image(), DEFECT_COLORS["disconnected"])
