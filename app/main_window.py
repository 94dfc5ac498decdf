"""The main window: the 3D view in the centre, dockable panels, menus, and the wiring between them.

Thin on purpose (silx's advice): loading and computing live in :mod:`app.session`, the model in
:mod:`app.scene`, drawing in :mod:`app.view`, file writing in :mod:`app.exports`.
"""

from __future__ import annotations

import html
import os
from typing import Any

from PySide6 import QtCore, QtGui, QtWidgets

from .exports import export_coloured_ply, export_results, with_thresholds, write_png
from .panels import BarcodePanel, DisplayPanel, HistogramPanel, PickPanel, SettingsPanel, SummaryPanel
from .panels._plot import preload_matplotlib
from .scene import METRICS, Scene, SceneEvent
from .session import Session
from .view import SceneView

MAX_RECENT = 10
FILE_FILTER = "Clouds and skeletons (*.ply *.pcd *.xyz *.txt *.csv *.pts *.obj *.off *.cg *.swc *.npy *.npz *.json);;All files (*)"


class _KeyEater(QtCore.QObject):
    """VTK's and pyvista's single-key bindings ('q' closes, 'w' wireframe, '+' resizes points behind
    the scene's back) are swallowed: the window's own shortcuts (listed in Help) act instead."""

    def eventFilter(self, obj: QtCore.QObject, event: QtCore.QEvent) -> bool:  # noqa: N802
        return event.type() in (QtCore.QEvent.Type.KeyPress, QtCore.QEvent.Type.KeyRelease)


class MainWindow(QtWidgets.QMainWindow):
    def __init__(self, settings: QtCore.QSettings | None = None, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle("SkelScope")
        self.resize(1500, 950)
        self.settings = settings if settings is not None else QtCore.QSettings("SkelScope", "skelscope")
        self.interactive = True  # False in the scripted mode: errors go to ``errors``, not dialogs
        self.errors: list[str] = []
        self.scene = Scene()
        self.session = Session(self.scene, self)
        self.view = SceneView(self.scene, self)
        self.setCentralWidget(self.view.widget)
        self._key_eater = _KeyEater(self)
        self.view.widget.installEventFilter(self._key_eater)
        self.view.plotter.drag_handler = self._drag
        self.view.plotter.drop_handler = self._drop
        self.setAcceptDrops(True)

        self.summary = SummaryPanel(self)
        self.barcodes = BarcodePanel(self)
        self.histogram = HistogramPanel(self)
        self.display = DisplayPanel(self.scene, self)
        self.settings_panel = SettingsPanel(self)
        self.pick = PickPanel(self)
        self.docks: dict[str, QtWidgets.QDockWidget] = {}
        right = QtCore.Qt.DockWidgetArea.RightDockWidgetArea
        self._dock("Summary", self.summary, right)
        self._dock("Barcodes", self.barcodes, right)
        self._dock("Histogram", self.histogram, right)
        self._dock("Display", self.display, QtCore.Qt.DockWidgetArea.LeftDockWidgetArea)
        self._dock("Picked element", self.pick, QtCore.Qt.DockWidgetArea.LeftDockWidgetArea)
        self._dock("Settings", self.settings_panel, QtCore.Qt.DockWidgetArea.LeftDockWidgetArea)
        self.tabifyDockWidget(self.docks["Barcodes"], self.docks["Histogram"])
        self.docks["Barcodes"].raise_()
        self._plots_stale: set[str] = set()
        self._plots_timer = QtCore.QTimer(self)
        self._plots_timer.setSingleShot(True)
        self._plots_timer.setInterval(20)
        self._plots_timer.timeout.connect(self._refresh_plots)
        for panel in (self.barcodes, self.histogram):
            panel.drawn.connect(self._plot_drawn)
        for dock in ("Barcodes", "Histogram"):
            self.docks[dock].visibilityChanged.connect(lambda visible: visible and self._schedule_plots())
        QtCore.QTimer.singleShot(0, self._size_docks)  # after the first layout, or Qt ignores it

        self._build_status_bar()
        self._build_menus()

        self.session.params_provider = self.settings_panel.params
        self.session.correspondence_provider = self.settings_panel.correspondence
        self.summary.cloud_colouring.connect(self.view.set_cloud_values)
        self.session.ask = self._ask
        self.session.error.connect(self.show_error)
        self.session.message.connect(lambda text: self.statusBar().showMessage(text, 8000))
        self.session.loaded.connect(lambda role, path: self._add_recent(path))
        runner = self.session.runner
        runner.started.connect(self._task_started)
        runner.progressed.connect(self._task_progress)
        runner.finished.connect(self._task_finished)
        runner.cancelled.connect(lambda name: self._task_finished(name) if not runner.running else None)
        self.summary.thresholds_changed.connect(self.scene.set_thresholds)
        self.view.on_pick = self._picked
        self.scene.subscribe(self._on_scene)
        self._update_actions()
        QtCore.QTimer.singleShot(1500, preload_matplotlib)  # after the first frame, off the GUI thread
        QtCore.QTimer.singleShot(4000, self._prepare_plots)

    # ---- construction ---------------------------------------------------------------------
    def _dock(self, title: str, widget: QtWidgets.QWidget, area: QtCore.Qt.DockWidgetArea) -> None:
        dock = QtWidgets.QDockWidget(title, self)
        dock.setObjectName(f"dock-{title}")
        dock.setWidget(widget)
        self.addDockWidget(area, dock)
        self.docks[title] = dock

    def _size_docks(self) -> None:
        self.resizeDocks([self.docks["Summary"], self.docks["Display"]], [420, 270], QtCore.Qt.Orientation.Horizontal)

    def _build_status_bar(self) -> None:
        bar = self.statusBar()
        # Fixed sizes: a status bar that re-lays itself out on every progress step makes Qt repaint the
        # window, and the 3D view re-renders (100+ ms for big clouds in software GL).
        self.stage = QtWidgets.QLabel("", self)
        self.stage.setFixedWidth(180)
        self.progress = QtWidgets.QProgressBar(self)
        self.progress.setRange(0, 1000)
        self.progress.setFixedWidth(220)
        self.progress.setTextVisible(False)
        self.cancel_button = QtWidgets.QPushButton("Cancel", self)
        self.cancel_button.clicked.connect(self.session.cancel)
        for w in (self.stage, self.progress, self.cancel_button):
            bar.addPermanentWidget(w)
            w.setVisible(False)
        # A constant height: showing the progress bar must not resize (and so re-render) the 3D view
        # and the plots.
        bar.setFixedHeight(max(self.cancel_button.sizeHint().height(), self.progress.sizeHint().height()) + 6)
        # Progress is shown at most 8 times a second: each repaint costs the GUI thread ~10 ms.
        self._pending_progress: tuple[float, str] | None = None
        self._progress_timer = QtCore.QTimer(self)
        self._progress_timer.setInterval(125)
        self._progress_timer.timeout.connect(self._show_progress)

    def _action(self, menu: QtWidgets.QMenu, text: str, slot: Any, shortcut: str | None = None,
                checkable: bool = False) -> QtGui.QAction:
        action = QtGui.QAction(text, self)
        if shortcut:
            action.setShortcut(QtGui.QKeySequence(shortcut))
            action.setShortcutContext(QtCore.Qt.ShortcutContext.WindowShortcut)
        action.setCheckable(checkable)
        action.triggered.connect(slot)
        menu.addAction(action)
        self.addAction(action)
        return action

    def _build_menus(self) -> None:
        mb = self.menuBar()
        self.actions_by_name: dict[str, QtGui.QAction] = {}
        a = self.actions_by_name
        m = mb.addMenu("&File")
        a["open"] = self._action(m, "Open files (roles decided automatically)…", self.open_files, "Ctrl+O")
        a["open_cloud"] = self._action(m, "Open cloud…", lambda: self.open_as("cloud"), "Ctrl+1")
        a["open_skeletal"] = self._action(m, "Open skeletal point set…", lambda: self.open_as("skeletal"), "Ctrl+2")
        a["open_curve"] = self._action(m, "Open curve skeleton…", lambda: self.open_as("curve"), "Ctrl+3")
        self.recent_menu = m.addMenu("Recent files")
        self._fill_recent()
        m.addSeparator()
        a["export_ply"] = self._action(m, "Export coloured PLY…", self.export_ply_dialog, "Ctrl+E")
        a["export_results"] = self._action(m, "Export results (JSON + CSV)…", self.export_results_dialog, "Ctrl+Shift+E")
        a["screenshot"] = self._action(m, "Save screenshot of the 3D view…", self.screenshot_dialog, "Ctrl+S")
        m.addSeparator()
        a["quit"] = self._action(m, "Quit", self.close, "Ctrl+Q")

        m = mb.addMenu("&Evaluate")
        a["evaluate"] = self._action(m, "Evaluate", self.session.start_evaluation, "F5")
        a["cancel"] = self._action(m, "Cancel", self.session.cancel, "Esc")
        m.addSeparator()
        for key, metric in zip(("B", "C", "S"), METRICS):
            a[f"metric_{metric}"] = self._action(m, f"Colour by {metric}", lambda _=False, mm=metric: self.scene.set_metric(mm), key)

        m = mb.addMenu("&View")
        a["reset"] = self._action(m, "Reset camera", self.view.reset_camera, "R")
        for key, (name, title) in zip(("1", "2", "3", "4", "5", "6", "0"), (
            ("xy", "Top (XY)"), ("-xy", "Bottom (-XY)"), ("xz", "Front (XZ)"), ("-xz", "Back (-XZ)"),
            ("yz", "Side (YZ)"), ("-yz", "Other side (-YZ)"), ("iso", "Isometric"),
        )):
            a[f"view_{name}"] = self._action(m, title, lambda _=False, n=name: self.view.standard_view(n), key)
        a["parallel"] = self._action(m, "Parallel projection", self.view.set_parallel_projection, "P", checkable=True)
        a["tubes"] = self._action(m, "Edges as tubes", self.scene.set_edges_as_tubes, "T", checkable=True)
        m.addSeparator()
        for dock in self.docks.values():
            m.addAction(dock.toggleViewAction())

        m = mb.addMenu("&Tools")
        a["skeletonize"] = self._action(m, "Skeletonize the cloud (Cao et al., the paper's)",
                                        self.session.start_skeletonize, "Ctrl+K")
        a["skeletonize_skelscope"] = self._action(m, "Skeletonize the cloud (SkelScope, with clean-up)",
                                                  lambda: self.session.start_skeletonize(method="skelscope"))
        a["study"] = self._action(m, "Study…", self.open_study, "Ctrl+Shift+S")

        m = mb.addMenu("&Help")
        a["help"] = self._action(m, "Keyboard shortcuts", self.show_shortcuts, "F1")
        a["about"] = self._action(m, "About SkelScope", self.show_about)

    # ---- dialogs --------------------------------------------------------------------------
    @QtCore.Slot(str, str, str)
    def show_error(self, title: str, message: str, details: str = "") -> None:
        """Errors never take the window down: a dialog (or, scripted, a recorded line)."""
        self.errors.append(message)
        if not self.interactive:
            return
        if details:
            box = QtWidgets.QMessageBox(QtWidgets.QMessageBox.Icon.Critical, title, message,
                                        QtWidgets.QMessageBox.StandardButton.Ok, self)
            box.setDetailedText(details)
            box.exec()
        else:
            QtWidgets.QMessageBox.critical(self, title, message)

    def _ask(self, question: str, options: list[str]) -> str | None:
        if not self.interactive:
            return options[0] if options else None
        item, ok = QtWidgets.QInputDialog.getItem(self, "Which file is which?", question, options, 0, False)
        return item if ok else None

    def shortcut_rows(self) -> list[tuple[str, str]]:
        rows = [(act.text().replace("&", "").rstrip("…"), act.shortcut().toString())
                for act in self.actions_by_name.values() if not act.shortcut().isEmpty()]
        rows += [("Rotate / pan / zoom", "left drag / middle drag / wheel"), ("Pick an element", "left click")]
        return rows

    def show_shortcuts(self) -> None:
        body = "".join(f"<tr><td>{html.escape(t)}</td><td><b>{html.escape(k)}</b></td></tr>" for t, k in self.shortcut_rows())
        QtWidgets.QMessageBox.information(self, "Keyboard shortcuts", f"<table cellspacing=4>{body}</table>")

    def show_about(self) -> None:
        QtWidgets.QMessageBox.about(
            self, "About SkelScope",
            "SkelScope scores point-cloud skeletons with topological similarity, boundedness, centeredness "
            "and smoothness. Invalid (NaN) local values are drawn magenta.",
        )

    # ---- loading --------------------------------------------------------------------------
    def open_files(self) -> None:
        paths, _ = QtWidgets.QFileDialog.getOpenFileNames(self, "Open clouds and skeletons", self._last_dir(), FILE_FILTER)
        if paths:
            self.session.load_files(paths)

    def open_as(self, role: str) -> None:
        title = {"cloud": "Open cloud", "skeletal": "Open skeletal point set", "curve": "Open curve skeleton"}[role]
        path, _ = QtWidgets.QFileDialog.getOpenFileName(self, title, self._last_dir(), FILE_FILTER)
        if path:
            self.session.load_as(role, path)

    def _last_dir(self) -> str:
        recent = self.recent_files()
        return os.path.dirname(recent[0]) if recent else os.getcwd()

    def recent_files(self) -> list[str]:
        value = self.settings.value("recent_files", [])
        if isinstance(value, str):
            value = [value]
        return [str(v) for v in (value or [])]

    def _add_recent(self, path: str) -> None:
        path = os.path.abspath(path)
        files = [path] + [p for p in self.recent_files() if p != path]
        self.settings.setValue("recent_files", files[:MAX_RECENT])
        self._fill_recent()

    def _fill_recent(self) -> None:
        self.recent_menu.clear()
        files = self.recent_files()
        for path in files:
            act = self.recent_menu.addAction(os.path.basename(path))
            act.setToolTip(path)
            act.triggered.connect(lambda _=False, p=path: self.session.load_files([p]))
        self.recent_menu.setEnabled(bool(files))

    @staticmethod
    def _local_files(event: QtGui.QDropEvent) -> list[str]:
        data = event.mimeData()
        if data is None or not data.hasUrls():
            return []
        return [u.toLocalFile() for u in data.urls() if u.isLocalFile() and os.path.isfile(u.toLocalFile())]

    def _drag(self, event: QtGui.QDragEnterEvent) -> None:
        if self._local_files(event):
            event.acceptProposedAction()
        else:
            event.ignore()

    def _drop(self, event: QtGui.QDropEvent) -> None:
        paths = self._local_files(event)
        if not paths:
            event.ignore()
            return
        event.acceptProposedAction()
        self.session.load_files(paths)

    dragEnterEvent = _drag  # drops on the panels work too  # noqa: N815
    dragMoveEvent = _drag  # noqa: N815
    dropEvent = _drop  # noqa: N815

    # ---- computing ------------------------------------------------------------------------
    def _task_started(self, name: str) -> None:
        self.stage.setText(f"{name}…")
        self.progress.setValue(0)
        for w in (self.stage, self.progress, self.cancel_button):
            w.setVisible(True)
        self._update_actions()

    def _task_progress(self, fraction: float, stage: str) -> None:
        self._pending_progress = (fraction, stage)
        if not self._progress_timer.isActive():
            self._show_progress()
            self._progress_timer.start()

    def _show_progress(self) -> None:
        if self._pending_progress is None:
            self._progress_timer.stop()
            return
        fraction, stage = self._pending_progress
        self._pending_progress = None
        self.progress.setValue(int(round(fraction * 1000)))
        if self.stage.text() != stage:
            self.stage.setText(stage)

    def _task_finished(self, _name: str) -> None:
        if self.session.runner.running:
            return
        self._progress_timer.stop()
        self._pending_progress = None
        for w in (self.stage, self.progress, self.cancel_button):
            w.setVisible(False)
        self._update_actions()

    # ---- scene -> panels ------------------------------------------------------------------
    def _on_scene(self, event: SceneEvent) -> None:
        if event.kind in ("quantities", "thresholds"):
            ev = self.scene.evaluation
            if event.kind == "quantities" and ev is not None:
                self.summary.set_thresholds(self.scene.beta_star, self.scene.c_star)
            self.summary.show_summary(self.scene.summary(), ev)
            if event.kind == "quantities":
                self._plots_stale.add("barcodes")
                self.pick.show_info(None)
            self._plots_stale.add("histogram")
            self._schedule_plots()
        elif event.kind in ("colouring", "display"):
            self._plots_stale.add("histogram")
            self._schedule_plots()
        elif event.kind == "layer":
            self.pick.show_info(None)
            names = [os.path.basename(layer.path) for layer in self.scene.layers.values() if layer.path]
            self.setWindowTitle("SkelScope" + (f" — {', '.join(names)}" if names else ""))
        self._update_actions()

    def _prepare_plots(self) -> None:
        """Make the barcode axes while idle (once matplotlib is loaded), not when a result lands."""
        import sys

        if "matplotlib.backends.backend_qtagg" in sys.modules and self.scene.evaluation is None:
            self.barcodes.prepare()
        elif "matplotlib.backends.backend_qtagg" not in sys.modules:
            QtCore.QTimer.singleShot(1000, self._prepare_plots)

    def _schedule_plots(self) -> None:
        """Plots are redrawn one per event-loop turn (making the artists in one turn, drawing them in
        the next), only when their panel is on screen, and only after the 3D view's pending frame,
        so a result landing never blocks the window for the sum of every redraw."""
        self.view.after_render(self._plots_timer.start)

    def _refresh_plots(self) -> None:
        if self.barcodes.draw_pending or self.histogram.draw_pending:
            return  # the panel's draw comes first; its ``drawn`` restarts this
        ev = self.scene.evaluation
        for name, panel, dock in (("barcodes", self.barcodes, "Barcodes"), ("histogram", self.histogram, "Histogram")):
            if name in self._plots_stale and not self.docks[dock].visibleRegion().isEmpty():
                self._plots_stale.discard(name)
                if name == "barcodes":
                    panel.show_topology(None if ev is None else ev.topology)
                else:
                    panel.show_scene(self.scene)
                return

    def _plot_drawn(self) -> None:
        if self._plots_stale:
            self._plots_timer.start()  # the next stale plot, after the event loop has turned

    def _picked(self, info: dict[str, Any] | None) -> None:
        self.pick.show_info(info)
        if info is not None:
            self.statusBar().showMessage(f"{info['element']} #{info['index']}", 5000)

    def _update_actions(self) -> None:
        a = self.actions_by_name
        has_eval = self.scene.evaluation is not None
        running = self.session.runner.running
        a["evaluate"].setEnabled(self.scene.can_evaluate())
        a["cancel"].setEnabled(running)
        a["export_ply"].setEnabled(has_eval)
        a["export_results"].setEnabled(has_eval)
        a["skeletonize"].setEnabled(self.scene.cloud is not None)
        a["skeletonize_skelscope"].setEnabled(self.scene.cloud is not None)
        a["study"].setEnabled(self.scene.cloud is not None and bool(self.scene.cloud.path) and _study_available())

    def open_study(self) -> None:
        try:
            from .study_dialog import StudyDialog
        except ImportError as exc:
            self.show_error("Study", f"the study dialog is not available ({exc})")
            return
        cloud = self.scene.cloud
        if cloud is None or not cloud.path:
            self.show_error("Study", "load a cloud from a file first")
            return
        dialog = StudyDialog(self, cloud.path)
        dialog.show()
        self._study_dialog = dialog

    def open_variant(self, cloud: Any, skeletal: Any = None, curve: Any = None, evaluation: Any = None) -> None:
        """Called by the Study dialog: show one variant (arrays, no files) in the 3D view."""
        self.session.show_arrays(cloud, skeletal, curve, evaluation)
        self.view.reset_camera()

    # ---- exports --------------------------------------------------------------------------
    def _shown_evaluation(self) -> Any:
        ev = self.scene.evaluation
        return None if ev is None else with_thresholds(ev, self.scene.beta_star, self.scene.c_star)

    def _inputs(self) -> tuple[str, ...]:
        return tuple(p for p in self.scene.input_paths().values() if p)

    def export_ply(self, out_dir: str) -> list[str]:
        ev = self._shown_evaluation()
        if ev is None:
            raise ValueError("nothing to export: run an evaluation first")
        return export_coloured_ply(ev, out_dir, self._inputs(), color_by=self.scene.metric)

    def export_results(self, prefix: str) -> list[str]:
        ev = self._shown_evaluation()
        if ev is None:
            raise ValueError("nothing to export: run an evaluation first")
        return export_results(ev, prefix, self._inputs())

    def save_screenshot(self, path: str, scale: int = 1, transparent: bool = False) -> str:
        return write_png(path, self.view.image(scale=scale, transparent=transparent), self._inputs())

    def _guarded(self, what: str, fn: Any, *args: Any) -> Any:
        try:
            out = fn(*args)
        except (ValueError, OSError) as exc:
            self.show_error(f"{what} failed", str(exc))
            return None
        self.statusBar().showMessage(f"{what}: wrote {', '.join(os.path.basename(p) for p in ([out] if isinstance(out, str) else out))}", 8000)
        return out

    def export_ply_dialog(self) -> None:
        folder = QtWidgets.QFileDialog.getExistingDirectory(self, "Export coloured PLY into", self._last_dir())
        if folder:
            self._guarded("PLY export", self.export_ply, folder)

    def export_results_dialog(self) -> None:
        path, _ = QtWidgets.QFileDialog.getSaveFileName(self, "Export results (PREFIX.json and PREFIX_*.csv)",
                                                        os.path.join(self._last_dir(), "results.json"), "JSON (*.json)")
        if path:
            self._guarded("Results export", self.export_results, path)

    def screenshot_dialog(self) -> None:
        path, _ = QtWidgets.QFileDialog.getSaveFileName(self, "Save screenshot", os.path.join(self._last_dir(), "view.png"), "PNG (*.png)")
        if not path:
            return
        scale, ok = QtWidgets.QInputDialog.getInt(self, "Screenshot", "Scale factor", 2, 1, 8)
        if not ok:
            return
        transparent = QtWidgets.QMessageBox.question(self, "Screenshot", "Transparent background?") == \
            QtWidgets.QMessageBox.StandardButton.Yes
        if not path.lower().endswith(".png"):
            path += ".png"
        self._guarded("Screenshot", self.save_screenshot, path, scale, transparent)

    # ---- closing --------------------------------------------------------------------------
    def closeEvent(self, event: QtGui.QCloseEvent) -> None:  # noqa: N802
        self.session.runner.shutdown()
        self.view.close()
        super().closeEvent(event)


def _study_available() -> bool:
    import importlib.util

    return importlib.util.find_spec("app.study_dialog") is not None
