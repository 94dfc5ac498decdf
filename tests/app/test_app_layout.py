"""The window fits a laptop screen: 1366 x 768 at scale 1, and at Qt scale factors 1.5 and
2 (checked in a fresh process under an Xvfb of that size, since the factor is read at start-up); the
status bar with the progress bar and Cancel stays on screen; every dock can be reached (shown, or a
tab beside a shown one, its panel scrolling when the dock is smaller than the panel) and, once
closed, can be opened again from the View menu."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from PySide6 import QtWidgets

from shape_files import write_shape_files
from skelcore import shapes

pytestmark = [pytest.mark.gui]

ROOT = Path(__file__).resolve().parents[2]
LAPTOP = (1366, 768)
TITLE_BAR = 48  # the room window_size.FRAME_ALLOWANCE leaves for a window manager's frame


def test_the_minimum_size_fits_a_1366x768_screen_with_room_for_a_title_bar(window):
    hint = window.minimumSizeHint()
    assert hint.width() <= LAPTOP[0] and hint.height() <= LAPTOP[1] - TITLE_BAR, hint
    # and it is not an accident of empty panels: with data and results it still fits
    sh = shapes.y_shape(600, seed=2)
    window.scene.set_cloud(sh.cloud)
    window.scene.set_skeletal(sh.skeletal)
    hint = window.minimumSizeHint()
    assert hint.width() <= LAPTOP[0] and hint.height() <= LAPTOP[1] - TITLE_BAR, hint


def test_every_dock_scrolls_its_panel_and_the_tall_columns_are_tabbed(window):
    for name, dock in window.docks.items():
        area = dock.widget()
        assert isinstance(area, QtWidgets.QScrollArea) and area.widgetResizable(), name
        # the dock asks for little: its panel scrolls instead
        assert dock.minimumSizeHint().height() < 150, (name, dock.minimumSizeHint())
    assert window.docks["Settings"] in window.tabifiedDockWidgets(window.docks["Display"])
    assert window.docks["Histogram"] in window.tabifiedDockWidgets(window.docks["Barcodes"])


def test_each_tab_group_has_one_tab_bar_even_before_the_event_loop_runs(qtbot, tmp_path):
    """Qt 6.11 gives the second tab group made in a hidden window a second tab bar, drawn over the
    "Picked element" dock until the event loop deletes it (deleteLater): a script that only calls
    processEvents (the scripted mode, make_screenshots) kept it. The window makes its left tabs on
    the first show instead."""
    from PySide6 import QtCore

    from skelscope.main_window import MainWindow

    w = MainWindow(settings=QtCore.QSettings(str(tmp_path / "s.ini"), QtCore.QSettings.Format.IniFormat))
    qtbot.addWidget(w)
    w.show()
    for _ in range(5):
        QtWidgets.QApplication.processEvents()  # no event loop: no deferred deletion
    bars = [b for b in w.findChildren(QtWidgets.QTabBar) if b.isVisible()]
    groups = sorted(tuple(b.tabText(i) for i in range(b.count())) for b in bars)
    assert groups == [("Barcodes", "Histogram", "Defects", "History"), ("Display", "Settings")], groups
    for bar in bars:  # no bar over a dock outside its group
        tabs = [bar.tabText(i) for i in range(bar.count())]
        for name, dock in w.docks.items():
            if dock.isVisible() and name not in tabs:
                assert not bar.geometry().intersects(dock.geometry()), (tabs, name)


def test_the_initial_size_is_the_screen_s_free_area_on_a_small_screen():
    from PySide6 import QtCore

    from skelscope.window_size import DEFAULT_SIZE, initial_size

    assert initial_size(QtCore.QSize(1920, 1200)) == DEFAULT_SIZE
    w, h = initial_size(QtCore.QSize(*LAPTOP))
    assert w <= LAPTOP[0] and h <= LAPTOP[1] - TITLE_BAR and w >= 1300 and h >= 700


@pytest.mark.window(dialogs="record")
def test_a_closed_dock_stays_in_the_view_menu_and_comes_back_from_it(window, qtbot):
    view_menu = next(a.menu() for a in window.menuBar().actions() if a.text().replace("&", "") == "View")
    for name in ("Support", "Picked element", "Settings", "Summary"):
        dock = window.docks[name]
        toggle = dock.toggleViewAction()
        dock.close()  # the dock's ✕
        qtbot.waitUntil(lambda d=dock: not d.isVisible())
        assert toggle in view_menu.actions() and toggle.text() == name and not toggle.isChecked(), name
        toggle.trigger()
        qtbot.waitUntil(lambda d=dock: d.isVisible())
        assert toggle.isChecked(), name
    # the Support dock added by its controller: listed after the window's own docks, not lost
    texts = [a.text() for a in view_menu.actions()]
    assert texts.count("Support") == 1 and texts.index("Support") > texts.index("Settings")


_PROBE = r"""
import json, sys
from PySide6 import QtCore, QtWidgets
app = QtWidgets.QApplication(["probe"])
from skelscope.main_window import MainWindow
w = MainWindow(settings=QtCore.QSettings(sys.argv[1], QtCore.QSettings.Format.IniFormat))
w.session.ask = lambda q, o: o[0]
w.show()
def settle(ms=300):
    loop = QtCore.QEventLoop(); QtCore.QTimer.singleShot(ms, loop.quit); loop.exec()
settle()
w.session.load_files(sys.argv[2:5])
if w.session.runner.running:
    loop = QtCore.QEventLoop(); w.session.runner.finished.connect(loop.quit); loop.exec()
settle()
w.session.start_evaluation()  # the status bar's stage, progress bar and Cancel on screen
app.processEvents()
screen = w.screen().availableGeometry()
def rect(r): return [r.x(), r.y(), r.width(), r.height()]
def global_rect(widget):
    return rect(QtCore.QRect(widget.mapToGlobal(QtCore.QPoint(0, 0)), widget.size()))
out = {"screen": rect(screen), "min": [w.minimumSizeHint().width(), w.minimumSizeHint().height()],
       "frame": rect(w.frameGeometry()), "status": global_rect(w.statusBar()),
       "status_visible": w.statusBar().isVisible(),
       "cancel": global_rect(w.cancel_button), "cancel_visible": w.cancel_button.isVisible(), "docks": {}}
view_menu = [a.menu() for a in w.menuBar().actions() if a.text().replace("&", "") == "View"][0]
for name, dock in w.docks.items():
    shown_tab = [d for d in w.tabifiedDockWidgets(dock) if d.isVisible() and not d.visibleRegion().isEmpty()]
    dock.raise_()
    settle(100)
    area = dock.widget()
    panel = area.widget()
    bar = area.verticalScrollBar()
    out["docks"][name] = {
        "visible": dock.isVisible() and not dock.visibleRegion().isEmpty(), "tab_beside_shown": bool(shown_tab),
        "rect": global_rect(dock), "viewport": [area.viewport().width(), area.viewport().height()],
        "panel_min_h": panel.minimumSizeHint().height(), "scroll_max": bar.maximum(),
        "in_view_menu": dock.toggleViewAction() in view_menu.actions()}
print("PROBE " + json.dumps(out), flush=True)
"""

# the end of a probe
_CLOSE = r"""
w.session.runner.shutdown()
w.close()
"""


@pytest.fixture(scope="module")
def sample_files(tmp_path_factory):
    return write_shape_files(tmp_path_factory.mktemp("layout"), shapes.y_shape(1500, seed=3))


def _inside(inner, outer) -> bool:
    x, y, w, h = inner
    ox, oy, ow, oh = outer
    return x >= ox and y >= oy and x + w <= ox + ow and y + h <= oy + oh


@pytest.fixture(scope="module")
def probes(sample_files, tmp_path_factory, request):
    """Runs of the probes by scale factor: each a fresh process under its own Xvfb screen of 1366 x 768
    pixels; at 1.5 the content probe follows in the same process. The probes this module's selected tests
    ask for all start when the first is asked for and run side by side (a probe waits for its window's
    events about a fifth of its time, which the others fill); each searches a free display from its own
    number on. Returns the dict of what each probe printed (its "PROBE" and "CONTENT" lines), by scale."""
    if shutil.which("xvfb-run") is None:
        pytest.skip("xvfb-run not installed")
    wanted = sorted({item.callspec.params.get("scale", "1.5") if hasattr(item, "callspec") else "1.5"
                     for item in request.session.items
                     if item.module is request.module and "probes" in item.fixturenames})
    running: dict[str, subprocess.Popen] = {}
    made: dict[str, dict] = {}

    def start(scale: str, display: int) -> subprocess.Popen:
        env = dict(os.environ, QT_SCALE_FACTOR=scale, QT_QPA_PLATFORM="xcb",
                   PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
        env.pop("DISPLAY", None)
        script = _PROBE + _CLOSE + (_CONTENT_PROBE + _CLOSE if scale == "1.5" else "")
        cmd = ["xvfb-run", "-a", "-n", str(display), "-s", f"-screen 0 {LAPTOP[0]}x{LAPTOP[1]}x24", sys.executable,
               "-c", textwrap.dedent(script), str(tmp_path_factory.mktemp("probe") / "s.ini"),
               sample_files["cloud"], sample_files["skeletal"], sample_files["curve"]]
        return subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT, env=env)

    def get(scale: str) -> dict:
        if not running:
            for i, s in enumerate(wanted or [scale]):
                running[s] = start(s, 200 + 100 * i)
        if scale not in running:
            running[scale] = start(scale, 200 + 100 * len(running))
        if scale not in made:
            stdout, stderr = running[scale].communicate(timeout=300)
            lines = dict(ln.split(" ", 1) for ln in stdout.splitlines() if ln.startswith(("PROBE ", "CONTENT ")))
            made[scale] = {"run": stdout + stderr, **{k: json.loads(v) for k, v in lines.items()}}
        return made[scale]

    yield get
    for proc in running.values():  # a probe no test waited for (a test failed before asking)
        if proc.poll() is None:
            proc.kill()
        proc.communicate()


@pytest.mark.slow
@pytest.mark.parametrize("scale", ["1", "1.5", "2"])
def test_at_each_scale_factor_the_window_fits_1366x768_and_every_dock_is_reachable(scale, probes):
    """A fresh process under its own Xvfb screen of 1366 x 768 pixels (683 x 384 device-independent
    pixels at scale 2); no window manager, so the window's own geometry is what the screen shows."""
    probe = probes(scale)
    assert "PROBE" in probe, probe["run"]
    got = probe["PROBE"]
    screen = got["screen"]
    expected = [round(v / float(scale)) for v in LAPTOP]
    assert abs(screen[2] - expected[0]) <= 1 and abs(screen[3] - expected[1]) <= 1, screen  # the factor applied
    assert got["min"][0] <= screen[2] and got["min"][1] <= screen[3], got["min"]
    assert _inside(got["frame"], screen), (got["frame"], screen)
    assert got["status_visible"] and _inside(got["status"], screen), got["status"]
    assert got["cancel_visible"] and _inside(got["cancel"], screen), got["cancel"]
    for name, dock in got["docks"].items():
        assert dock["visible"] or dock["tab_beside_shown"], (name, dock)
        assert dock["in_view_menu"], name
        assert _inside(dock["rect"], screen), (name, dock["rect"], screen)
        # raised, the panel shows through its scroll area: whole, or by scrolling to the rest
        assert dock["viewport"][1] > 0 and dock["viewport"][1] + dock["scroll_max"] >= dock["panel_min_h"], (name, dock)


# The content checks, run after the scale-1.5 layout probe in the same process (one start-up of the
# interpreter and the viewer's imports instead of two) on a second window of its own, with its own
# settings file, given the whole screen before it is shown.
_CONTENT_PROBE = r"""
from skelscope.panels.settings import ElidingComboBox
w = MainWindow(settings=QtCore.QSettings(sys.argv[1] + ".content.ini", QtCore.QSettings.Format.IniFormat))
w.session.ask = lambda q, o: o[0]
w.setGeometry(w.screen().availableGeometry())
w.show()
settle()
w.session.load_files(sys.argv[2:5])
while w.session.runner.running:
    settle(200)
settle()
out = {"docks": {}}
for name, dock in w.docks.items():
    dock.raise_()
    settle(150)
    area = dock.widget()
    out["docks"][name] = {"hscroll": area.horizontalScrollBar().maximum(), "viewport": area.viewport().width(),
                          "panel_min": area.widget().minimumSizeHint().width()}
# the Summary: every column inside the table, every header line and every cell's unbreakable part in its column
w.docks["Summary"].raise_(); settle(150)
t = w.summary.table
fm = t.fontMetrics()
cols = [t.columnWidth(c) for c in range(t.columnCount())]
out["summary"] = {"columns": cols, "header": t.verticalHeader().width(), "table_viewport": t.viewport().width(),
                  "too_wide": []}
for c in range(t.columnCount()):
    for line in t.horizontalHeaderItem(c).text().split("\n"):
        if fm.horizontalAdvance(line) > cols[c] - 4:
            out["summary"]["too_wide"].append(line)
    for r in range(t.rowCount()):
        for line in t.item(r, c).text().split("\n"):
            for word in line.split(" "):
                if fm.horizontalAdvance(word) > cols[c] - 4:
                    out["summary"]["too_wide"].append(word)
# the Settings: labels whole, combo values whole or elided with their full text in the tooltip
w.docks["Settings"].raise_(); settle(150)
panel = w.settings_panel if hasattr(w, "settings_panel") else w.docks["Settings"].widget().widget()
out["settings"] = {"labels_cut": [], "combos": []}
for label in panel.findChildren(QtWidgets.QLabel):
    if label.isVisible() and label.width() < label.sizeHint().width():
        out["settings"]["labels_cut"].append(label.text())
for combo in panel.findChildren(ElidingComboBox):
    out["settings"]["combos"].append([combo.currentText(), combo.shown_text(), combo.toolTip()])
# the barcode panel's title inside its figure
w.docks["Barcodes"].raise_(); settle(400)
fig = w.barcodes.figure
box = w.barcodes._title.get_window_extent(renderer=w.barcodes.canvas.get_renderer())
ratio = float(getattr(w.barcodes.canvas, "device_pixel_ratio", 1.0) or 1.0)
out["barcode_title"] = {"x0": box.x0 / ratio, "x1": box.x1 / ratio, "width": fig.bbox.width / ratio,
                        "text": w.barcodes.title()}
# the tabs of tabbed docks: each title whole (the bar scrolls its tabs when they do not fit), also with
# the right-hand docks narrowed to 180 pixels
w.resizeDocks([w.docks["Barcodes"]], [180], QtCore.Qt.Orientation.Horizontal)
settle(300)
out["tabs"] = [[bar.tabText(i), bar.tabRect(i).width(), bar.fontMetrics().horizontalAdvance(bar.tabText(i))]
               for bar in w.findChildren(QtWidgets.QTabBar) if bar.isVisible() for i in range(bar.count())]
print("CONTENT " + json.dumps(out))
"""


def test_at_scale_1_5_on_1366x768_the_panels_show_their_content_whole(probes):
    """In a fresh window at QT_SCALE_FACTOR=1.5 (911 x 512 device-independent pixels) given the whole
    screen, after its evaluation: no dock scrolls sideways; the Summary shows
    both columns with every value and count whole; the Settings show every label whole and every
    choice whole or elided with its full text in the tooltip; the barcode panel's title keeps clear
    of the figure's edges; the docks' tabs show their titles whole."""
    probe = probes("1.5")
    assert "CONTENT" in probe, probe["run"]
    got = probe["CONTENT"]
    for name, dock in got["docks"].items():
        assert dock["hscroll"] == 0, (name, dock)
    summary = got["summary"]
    assert sum(summary["columns"]) <= summary["table_viewport"] + 2, summary  # both columns in view
    assert min(summary["columns"]) > 0 and summary["too_wide"] == [], summary
    settings = got["settings"]
    assert settings["labels_cut"] == [], settings
    for full, shown, tip in settings["combos"]:
        assert shown == full or (shown.endswith("…") and tip.startswith(full)), (full, shown, tip)
    assert {"Barcodes", "Histogram", "Defects", "History"} <= {t[0] for t in got["tabs"]}, got["tabs"]
    for text, width, needed in got["tabs"]:
        assert width >= needed, (text, width, needed)  # not "Barco…", "Def…"
    title = got["barcode_title"]
    assert title["x0"] >= 4 and title["x1"] <= title["width"] - 4, title
    assert "K = " in title["text"] and "d_Wp" in title["text"]
