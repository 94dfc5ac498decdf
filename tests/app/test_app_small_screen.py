"""The panels at the size they get on a 1366 x 768 screen at QT_SCALE_FACTOR 1.5 (911 x 512
device-independent pixels: a right-hand dock about 260 wide): no number is cut, no hint is cut
sideways (docs/guide/viewer.md "Colours, panels and thresholds")."""

from __future__ import annotations

import pytest
from PySide6 import QtCore, QtWidgets

pytestmark = pytest.mark.gui

DOCK_WIDTH = 260  # the Summary / Barcodes dock's panel at 1366 x 768, scale 1.5 (device-independent pixels)

#: a neuron's counts (754534424, 30k points: thousands of curve samples)
NEURON = {
    "topology": {"bottleneck": 0.0123, "wasserstein": 0.00456, "eps_star": 0.02, "n_bars": 47},
    "boundedness": {"skeletal": 0.912, "curve": 0.680},
    "centeredness": {"skeletal": 0.85, "curve": 0.059},
    "smoothness": {"skeletal": 0.7, "curve": 0.813},
    "counts": {
        "boundedness": {"skeletal": 30000, "curve": 4687},
        "centeredness": {"skeletal": 29871, "curve": 2751},
        "smoothness": {"skeletal": 30000, "curve": 3274},
    },
}


def _text_fits(view: QtWidgets.QTableView, row: int, column: int) -> tuple[bool, str]:
    """Whether a cell's text shows whole: every unbreakable part inside the column and every
    wrapped line inside the row (else Qt elides it with "…")."""
    item = view.item(row, column)
    text = item.text()
    fm = view.fontMetrics()
    margin = 2 * (view.style().pixelMetric(QtWidgets.QStyle.PixelMetric.PM_FocusFrameHMargin, None, view) + 1)
    width = view.columnWidth(column) - margin
    for word in text.replace("\n", " ").split(" "):
        if fm.horizontalAdvance(word) > width:
            return False, f"{word!r} is {fm.horizontalAdvance(word)} px in a {width} px column"
    flags = int(QtCore.Qt.TextFlag.TextWordWrap.value) | int(QtCore.Qt.AlignmentFlag.AlignCenter.value)
    need = fm.boundingRect(QtCore.QRect(0, 0, width, 10_000), flags, text).height()
    if need > view.rowHeight(row):
        return False, f"{text!r} needs {need} px in a {view.rowHeight(row)} px row"
    return True, ""


def test_the_summary_shows_every_count_whole_in_a_narrow_dock(qtbot):
    """4,687 curve samples once showed as "(n = 468…": a number that reads as another one."""
    from skelscope.panels.summary import SummaryPanel

    panel = SummaryPanel()
    qtbot.addWidget(panel)
    panel.resize(DOCK_WIDTH, 600)
    panel.show()
    panel.show_summary(NEURON)
    qtbot.waitExposed(panel)
    QtWidgets.QApplication.processEvents()
    table = panel.table
    assert sum(table.columnWidth(c) for c in range(table.columnCount())) <= table.viewport().width() + 2
    shown = [table.item(r, c).text() for r in range(table.rowCount()) for c in range(table.columnCount())]
    assert any("4,687" in t for t in shown) and any("30,000" in t for t in shown), shown  # thousands separated
    for r in range(table.rowCount()):
        for c in range(table.columnCount()):
            ok, why = _text_fits(table, r, c)
            assert ok, why


def test_the_barcode_hint_is_never_cut_sideways(qtbot):
    """Before the figure exists (a label) and after (the figure's text): the hint wraps to the panel,
    no line wider than it ("… after an evaluat" once ran off both edges)."""
    from skelscope.panels.barcode import BarcodePanel

    panel = BarcodePanel()
    qtbot.addWidget(panel)
    panel.resize(DOCK_WIDTH, 400)
    panel.show()
    qtbot.waitExposed(panel)
    label = panel._hint
    assert label.isVisible() and label.minimumSizeHint().width() <= DOCK_WIDTH
    fm = label.fontMetrics()
    assert fm.boundingRect(QtCore.QRect(0, 0, label.width(), 10_000), int(QtCore.Qt.TextFlag.TextWordWrap.value),
                           label.text()).width() <= label.width()
    narrow = 180  # narrower still: the figure's hint on three lines or more, none cut
    for width in (DOCK_WIDTH, narrow):
        panel.resize(width, 400)
        panel.prepare()
        panel.show_topology(None)
        qtbot.waitUntil(lambda: not panel.draw_pending)
        QtWidgets.QApplication.processEvents()
        fig = panel.figure
        box = panel._empty.get_window_extent(renderer=panel.canvas.get_renderer())
        assert panel._empty.get_visible() and "evaluation" in panel._empty.get_text()
        assert box.x0 >= 0 and box.x1 <= fig.bbox.width, (width, box, fig.bbox.width)


def _legend_text_height(dpi: int, size: tuple[int, int]) -> int:
    """The tallest run of dark rows (black text) inside the defect legend's box, in pixels."""
    import numpy as np
    import pyvista as pv

    from skelscope.view.defect_overlay import LEGEND_LABELS, defect_legend, keep_fitted

    keys = ["incomplete", "spurious_branches", "outside"]
    plotter = pv.Plotter(off_screen=True, window_size=size)
    try:
        plotter.ren_win.SetDPI(dpi)  # what pyvistaqt sets: 72 x the device pixel ratio
        legend = defect_legend(keys)
        plotter.renderer.AddViewProp(legend)
        keep_fitted(legend, plotter.renderer, [LEGEND_LABELS[k] for k in keys])
        img = np.asarray(plotter.screenshot(return_img=True))[..., :3].astype(int)
        h, w = img.shape[:2]
        (x0, y0), (bw, bh) = legend.GetPosition(), legend.GetPosition2()
        box = img[int(h * (1 - y0 - bh)) + 2:int(h * (1 - y0)) - 2, int(w * x0) + 2:int(w * (x0 + bw)) - 2]
        assert x0 >= 0 and x0 + bw <= 1, (x0, bw)  # inside the view
        dark = (box.max(axis=-1) < 80).any(axis=1)
        runs, run = [], 0
        for on in dark:
            run = run + 1 if on else 0
            runs.append(run)
        return max(runs)
    finally:
        plotter.close()


def test_the_defect_legend_text_grows_with_the_device_pixel_ratio():
    """At QT_SCALE_FACTOR 1.5 the text is drawn at 1.5 x 72 DPI, in points as the colour bar's
    labels are (it was about 7 pixels high, fitted to a box that did not grow)."""
    size = (520, 620)  # the 3-D view at 1366 x 768, scale 1.5 (device pixels)
    one, scaled = _legend_text_height(72, size), _legend_text_height(108, size)
    assert scaled >= 12, scaled
    assert 1.3 <= scaled / one <= 1.7, (one, scaled)
