"""The main window: the 3D view in the centre, dockable panels, menus, and the wiring between them.

Thin on purpose (silx's advice): loading and computing live in :mod:`skelscope.session`, the model in
:mod:`skelscope.scene`, drawing in :mod:`skelscope.view`, file writing in :mod:`skelscope.exports`.
"""

from __future__ import annotations

import html
import os
from typing import Any, Callable

from PySide6 import QtCore, QtGui, QtWidgets

from .actions import Menus
from .exports import (
    data_stem, export_coloured_ply, export_results, ply_export_names, result_export_names, with_thresholds, write_png,
)
from .gui_collector import CollectorHold
from .panels import BarcodePanel, DisplayPanel, HistogramPanel, PickPanel, SettingsPanel, SummaryPanel
from .panels._plot import preload_matplotlib
from .scene import LAYER_ORDER, METRICS, Scene, SceneEvent
from .session import Session, preload_engine
from .status_bar import StatusBar
from .view import SceneView
from .window_api import LEFT, RIGHT, ActionSpec
from .window_size import initial_size

MAX_RECENT = 10
OPEN_INDEX = "Open skeletal index…"
MAP_SKELETON = "Map skeleton into the cloud's frame…"
INDEX_FILTER = "Skeletal index (*.txt *.csv *.npy);;All files (*)"
FILE_FILTER = "Clouds and skeletons (*.ply *.pcd *.xyz *.txt *.csv *.pts *.obj *.off *.cg *.swc *.npy *.npz *.json);;All files (*)"


class _KeyEater(QtCore.QObject):
    """VTK's and pyvista's single-key bindings ('q' closes, 'w' wireframe, '+' resizes points behind
    the scene's back) are swallowed: the window's own shortcuts (listed in Help) act instead."""

    def eventFilter(self, obj: QtCore.QObject, event: QtCore.QEvent) -> bool:  # noqa: N802
        return event.type() in (QtCore.QEvent.Type.KeyPress, QtCore.QEvent.Type.KeyRelease)


class MainWindow(QtWidgets.QMainWindow):
    """The viewer's window; feature controllers see it as :class:`skelscope.window_api.WindowApi`."""

    element_picked = QtCore.Signal(object)  # info dict of the picked element, or None (after the pick panel)
    closing = QtCore.Signal()  # emitted first thing in closeEvent

    def __init__(self, settings: QtCore.QSettings | None = None, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle("SkelScope")
        self.resize(*initial_size(self.screen().availableGeometry().size()))
        self.settings = settings if settings is not None else QtCore.QSettings("SkelScope", "skelscope")
        self.interactive = True  # False in the scripted mode: errors go to ``errors``, not dialogs
        self.errors: list[str] = []
        self.bug: str | None = None  # an uncaught exception's traceback (the scripted mode exits 1)
        self._collector_hold = CollectorHold()  # cyclic collection on this thread while the window is open
        self.destroyed.connect(self._collector_hold.release)  # (a window never closed)
        self.scene = Scene()
        self.session = Session(self.scene, self)
        self.view = SceneView(self.scene, self)
        self.session.after_scores = self.view.after_render  # an edit's defects after its recoloured frame
        self.session.hold_frames, self.session.release_frames = self.view.hold_frames, self.view.release_frames
        self.session.draw_now = self.view.draw_now  # an edit's recoloured frame before the panels' repaint
        self.setCentralWidget(self.view.widget)
        self._key_eater = _KeyEater(self)
        self.view.widget.installEventFilter(self._key_eater)
        self._drop_handlers: list[tuple[Callable[[list[str]], bool], Callable[[list[str]], None]]] = []
        self.view.plotter.drag_handler = self._drag
        self.view.plotter.drop_handler = self._drop
        self.setAcceptDrops(True)
        self.menus = Menus(self.menuBar(), self)
        self.actions_by_name: dict[str, QtGui.QAction] = self.menus.actions

        self.summary = SummaryPanel(self)
        self.barcodes = BarcodePanel(self)
        self.histogram = HistogramPanel(self)
        self.display = DisplayPanel(self.scene, self)
        self.settings_panel = SettingsPanel(self)
        self.pick = PickPanel(self)
        self.docks: dict[str, QtWidgets.QDockWidget] = {}
        self.add_dock("Summary", self.summary, RIGHT)
        self.add_dock("Barcodes", self.barcodes, RIGHT)
        self.add_dock("Histogram", self.histogram, RIGHT)
        self.add_dock("Display", self.display, LEFT)
        self.add_dock("Picked element", self.pick, LEFT)
        self.add_dock("Settings", self.settings_panel, LEFT)
        # Tabs where a column would need more height than a laptop has (the window fits 1366 x 768). The
        # left column's are made when the window is first shown (showEvent); till then Settings is
        # hidden, so the column's minimum height is the tabbed one's.
        self.tabifyDockWidget(self.docks["Barcodes"], self.docks["Histogram"])
        self.docks["Barcodes"].raise_()
        self.docks["Settings"].hide()
        self._left_tabs_made = False
        self._plots_stale: set[str] = set()
        self._plots_timer = QtCore.QTimer(self)
        self._plots_timer.setSingleShot(True)
        self._plots_timer.setInterval(20)
        self._plots_timer.timeout.connect(self._refresh_plots)
        for panel in (self.barcodes, self.histogram):
            panel.drawn.connect(self._plot_drawn)
        for dock in ("Barcodes", "Histogram"):
            self.docks[dock].visibilityChanged.connect(lambda visible: visible and self._schedule_plots())
        QtCore.QTimer.singleShot(0, self, self._size_docks)  # after the first layout, or Qt ignores it

        self._build_status_bar()
        for spec in self.action_table():
            self.add_action(spec)

        self.session.params_provider = self.settings_panel.params
        self.session.correspondence_provider = self.settings_panel.correspondence
        self.session.scan_options_provider = self.settings_panel.scan_options
        self.session.set_correspondence = self.settings_panel.set_correspondence
        self.session.ask_file = self._ask_index_file
        # the scripted mode waits for the evaluation it starts: no deferral there
        self.session.after_render = lambda fn: self.view.after_render(fn) if self.interactive else fn()
        self.summary.cloud_colouring.connect(self.view.set_cloud_values)
        self.session.ask = self._ask
        self.session.error.connect(self.show_error)
        self.session.message.connect(self.show_message)
        self.session.loaded.connect(lambda role, path: self._add_recent(path))
        runner = self.session.runner
        runner.started.connect(self._task_started)
        runner.progressed.connect(self._task_progress)
        runner.finished.connect(self._task_finished)
        runner.cancelled.connect(lambda name: self._task_finished(name) if not runner.running else None)
        self.summary.thresholds_changed.connect(self.scene.set_thresholds)
        self.summary.rerun_requested.connect(self.session.start_evaluation)
        self.settings_panel.changed.connect(self.session.check_stale)
        self.session.stale_changed.connect(self._stale_changed)
        self.display.layer_action.connect(self._layer_action)
        self.view.on_pick = self.pick_element
        self.scene.subscribe(self._on_scene)
        # the feature controllers, each through the public interface (app.window_api)
        from .compare_run import RunBrowser
        from .compare_view import CompareController
        from .defects_controller import DefectsController
        from .edit_compare import EditCompare
        from .edit_controller import EditController
        from .saved_sessions import SavedSessions
        from .support_controller import SupportController
        from .viewpoint_controller import ViewpointController

        self.supports = SupportController(self)  # the picked element's support (dock, 3-D overlay, filter)
        self.defects = DefectsController(self)  # the Defects dock, the defects in 3-D, a clicked branch
        self.edits = EditController(self)  # Edit mode, undo / redo, History dock, File > Save skeleton as
        self.defects.row_actions = self.edits.row_actions  # a Defects row's "Prune this branch", ...
        self.defects.is_edit = lambda: self.edits.applying  # an edit keeps the skeleton's marks
        self.viewpoints = ViewpointController(self)  # Evaluate > Viewpoint from the camera / typed
        self.compare = CompareController(self)  # File > Compare with a second skeleton (B)
        self.edit_compare = EditCompare(self, self.edits)  # Edit > the loaded curve against the edited one (A/B)
        self.compare_run = RunBrowser(self)  # File > Open comparison run, and drops of a run
        self.saved_sessions = SavedSessions(self)  # File > Save / Open session, File > Recent
        self._update_actions()
        QtCore.QTimer.singleShot(1500, self, preload_matplotlib)  # after the first frame, off the GUI thread
        QtCore.QTimer.singleShot(2500, self, lambda: self.view.after_render(preload_engine))  # not during a frame
        QtCore.QTimer.singleShot(4000, self, self._prepare_plots)

    # ---- the interface for feature controllers (app.window_api.WindowApi) -----------------
    @property
    def widget(self) -> QtWidgets.QMainWindow:
        return self

    def add_dock(self, title: str, widget: QtWidgets.QWidget, area: QtCore.Qt.DockWidgetArea = LEFT,
                 below: str | None = None) -> QtWidgets.QDockWidget:
        """A dock named ``title`` in ``area`` (or split under the dock ``below``), listed in the View menu.

        The panel sits in a scroll area: a dock never asks for more room than the screen has (the
        window's minimum size stays small), a panel taller than its dock scrolls."""
        dock = QtWidgets.QDockWidget(title, self)
        dock.setObjectName(f"dock-{title}")
        dock.setWidget(scrolling(widget, dock))
        self.addDockWidget(area, dock)
        if below is not None:
            self.splitDockWidget(self.docks[below], dock, QtCore.Qt.Orientation.Vertical)
        self.docks[title] = dock
        self.menus.place("view.docks", dock.toggleViewAction())
        return dock

    def add_action(self, spec: ActionSpec) -> QtGui.QAction:
        """A menu action at the end of its group (:data:`skelscope.actions.MENUS`); its conditions are kept up."""
        action = self.menus.add(spec)
        self.menus.update()
        return action

    def add_drop_handler(self, accepts: Callable[[list[str]], bool], drop: Callable[[list[str]], None]) -> None:
        """Dropped paths (files or folders) that ``accepts`` takes go to ``drop`` instead of the loader."""
        self._drop_handlers.append((accepts, drop))

    def submenu(self, group: str) -> QtWidgets.QMenu:
        """The submenu a group is shown as (:data:`skelscope.actions.SUBMENUS`), for a controller to fill."""
        return self.menus.submenus[group]

    def set_settings(self, params: Any, correspondence: str, scan_options: dict[str, bool] | None = None) -> None:
        """The Settings panel's parameters, the thresholds beta*, c* (summary panel and scene), the
        correspondence mode and the real-scan options, from a ``skelcore.Params`` (a saved session)."""
        self.settings_panel.set_params(params)
        self.settings_panel.set_correspondence(correspondence)
        self.settings_panel.set_scan_options(**(scan_options or {}))
        self.scene.set_thresholds(params.beta_star, params.c_star)
        self.summary.set_thresholds(params.beta_star, params.c_star)

    def picked_element(self) -> dict[str, Any] | None:
        """The element shown in the pick panel (None when none is)."""
        return self.pick.info

    def select_element(self, layer: str, location: str, index: int) -> dict[str, Any]:
        """Pick an element by its index, as a click on it would: marked in 3D, then :meth:`pick_element`."""
        info = self.scene.element_info(layer, location, index)
        self.view.mark(info["xyz"])
        self.pick_element(info)
        return info

    def curve_edits(self) -> dict[str, Any] | None:
        """The edit log of the curve's edits done (None when it is not edited): saved in sessions."""
        return self.edits.edit_log()

    def replay_curve_edits(self, log: dict[str, Any]) -> list[str]:
        """A session's edit log replayed on the loaded curve (undoable); the problems as lines."""
        return self.edits.replay(log)

    def add_display_option(self, widget: QtWidgets.QWidget) -> None:
        """A control at the end of the Display panel."""
        self.display.add_option(widget)

    def last_dir(self) -> str:
        """Where file dialogs open: the folder of the last file loaded, else the working folder."""
        recent = self.recent_files()
        return os.path.dirname(recent[0]) if recent else os.getcwd()

    def input_files(self) -> tuple[str, ...]:
        """The loaded inputs' files (writers refuse to replace them)."""
        return tuple(p for p in self.scene.input_paths().values() if p)

    def pick_element(self, info: dict[str, Any] | None) -> None:
        """A pick (a click in the 3-D view; None clears): the pick panel, the status bar, ``element_picked``."""
        self.pick.show_info(info)
        if info is not None:
            self.show_message(f"{info['element']} #{info['index']}", 5000)
        # The text on screen now, before the marker's frame (seconds at full detail for millions of
        # points in software GL) and the support's computation (text after both: 2.3 s from the click).
        self.pick.text.viewport().repaint()
        self.element_picked.emit(info)

    def show_message(self, text: str, timeout_ms: int = 8000) -> None:
        self.statusBar().showMessage(text, timeout_ms)

    def report_bug(self, message: str, details: str) -> None:
        """An uncaught exception (the exception hook): kept in ``bug`` and shown like any error."""
        self.bug = details
        self.show_error("Unexpected error", message, details)

    # ---- construction ---------------------------------------------------------------------
    def _size_docks(self) -> None:
        """The side columns' first widths: their panels' natural widths, at most a third of the window
        together (a small screen, or a large scale factor, keeps most of the width for the 3D view)."""
        width, height = self.width(), self.height()
        bar = self.style().pixelMetric(QtWidgets.QStyle.PixelMetric.PM_ScrollBarExtent)
        right = min(420, int(0.3 * width))
        left = min(self.display.sizeHint().width() + bar + 8, int(0.3 * width))
        self.resizeDocks([self.docks["Summary"], self.docks["Display"]], [right, left], QtCore.Qt.Orientation.Horizontal)
        # the left column: the Display panel whole if the height allows, the picked element's few lines
        title = self.docks["Display"].minimumSizeHint().height() - self.docks["Display"].widget().minimumSizeHint().height()
        picked = self.pick.sizeHint().height() + title
        self.resizeDocks([self.docks["Display"], self.docks["Picked element"]],
                         [min(self.display.sizeHint().height() + title + 4, int(0.5 * height)),
                          min(picked, int(0.2 * height))], QtCore.Qt.Orientation.Vertical)

    def _build_status_bar(self) -> None:
        bar = StatusBar(self)  # its message elided beside the task widgets, whole in the tooltip
        self.setStatusBar(bar)
        # Fixed sizes: a status bar that re-lays itself out on every progress step makes Qt repaint the
        # window, and the 3D view re-renders (100+ ms for big clouds in software GL). They follow only
        # the window's width (``_size_task_widgets``).
        self.stage = QtWidgets.QLabel("", self)
        self.progress = QtWidgets.QProgressBar(self)
        self.progress.setRange(0, 1000)
        self.progress.setTextVisible(False)
        self._size_task_widgets()
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

    def _size_task_widgets(self) -> None:
        """The stage label and the progress bar: 320 and 220 px, at most 28 % and 10 % of the window's
        width, so that a small screen (911 px at 1366 x 768, scale 1.5) leaves the status message
        about half the bar and the stage still shows two stages ("skeletal boundedness + topology",
        200 px) down to 750 px (docs/guide/viewer.md "Sessions and small screens"). The stage's text
        is elided again to its new width."""
        stage, progress = min(320, int(0.28 * self.width())), min(220, self.width() // 10)
        if self.stage.width() != stage or self.progress.width() != progress:
            self.stage.setFixedWidth(stage)
            self.progress.setFixedWidth(progress)
            if self.stage.toolTip():
                self._set_stage_text(self.stage.toolTip())

    def resizeEvent(self, event: QtGui.QResizeEvent) -> None:  # noqa: N802
        super().resizeEvent(event)
        self._size_task_widgets()

    def action_table(self) -> list[ActionSpec]:
        """The window's own actions, one row each: name, text, menu group, what it does, shortcut, and
        when it is enabled or checked. Feature controllers add theirs with :meth:`add_action`."""
        scene, session, view = self.scene, self.session, self.view

        def has_eval() -> bool:
            return scene.evaluation is not None

        def has_cloud() -> bool:
            return scene.cloud is not None

        def can_study() -> bool:
            return scene.cloud is not None and bool(scene.cloud.path) and _study_available()

        A = ActionSpec  # noqa: N806
        return [
            A("open", "Open files (roles decided automatically)…", "file.open", self.open_files, "Ctrl+O"),
            A("open_cloud", "Open cloud…", "file.open", lambda: self.open_as("cloud"), "Ctrl+1"),
            A("open_skeletal", "Open skeletal point set…", "file.open", lambda: self.open_as("skeletal"), "Ctrl+2"),
            A("open_curve", "Open curve skeleton…", "file.open", lambda: self.open_as("curve"), "Ctrl+3"),
            A("open_index", OPEN_INDEX, "file.open", self.open_index_dialog,
              enabled=lambda: scene.skeletal is not None and scene.cloud is not None),
            *(A(f"close_{role}", f"Close the {_ROLE_TITLES[role]}", "file.close",
                lambda r=role: session.close_layer(r), enabled=lambda r=role: r in scene.layers)
              for role in LAYER_ORDER),
            A("close_all", "Close all", "file.close_all", session.close_all, "Ctrl+W", enabled=lambda: bool(scene.layers)),
            A("export_ply", "Export coloured PLY…", "file.export", self.export_ply_dialog, "Ctrl+E", enabled=has_eval),
            A("export_results", "Export results (JSON + CSV)…", "file.export", self.export_results_dialog,
              "Ctrl+Shift+E", enabled=has_eval),
            A("screenshot", "Save picture of the 3D view…", "file.export", self.screenshot_dialog, "Ctrl+S"),
            A("quit", "Quit", "file.quit", self.close, "Ctrl+Q"),
            A("evaluate", "Evaluate", "evaluate.run", session.start_evaluation, "F5", enabled=scene.can_evaluate),
            A("cancel", "Cancel", "evaluate.run", session.cancel, "Esc", enabled=lambda: session.runner.running),
            A("map_skeleton", MAP_SKELETON, "evaluate.run", self.map_skeleton_dialog,
              enabled=lambda: scene.cloud is not None and (scene.skeletal is not None or scene.curve is not None)),
            *(A(f"metric_{metric}", f"Colour by {metric}", "evaluate.colour", lambda m=metric: scene.set_metric(m), key)
              for key, metric in zip(("B", "C", "S"), METRICS)),
            A("reset", "Reset camera", "view.camera", view.reset_camera, "R"),
            *(A(f"view_{name}", title, "view.camera", lambda n=name: view.standard_view(n), key)
              for key, (name, title) in zip(("1", "2", "3", "4", "5", "6", "0"), _STANDARD_VIEWS)),
            A("parallel", "Parallel projection", "view.camera", view.set_parallel_projection, "P",
              checked=lambda: view.parallel_projection),
            A("tubes", "Edges as tubes", "view.style", scene.set_edges_as_tubes, "T", checked=lambda: scene.edges_as_tubes),
            *(A(f"style_{name}", title, "view.style", lambda on, n=name: scene.set_style(n, on), key,
                checked=lambda n=name: scene.style[n]) for name, title, key in _STYLES),
            A("save_camera", "Save camera…", "view.camera_files", self.save_camera_dialog),
            A("load_camera", "Load camera…", "view.camera_files", self.load_camera_dialog),
            A("skeletonize", "Skeletonize the cloud (Cao et al., the paper's)", "tools.skeletonize",
              session.start_skeletonize, "Ctrl+K", enabled=has_cloud),
            A("skeletonize_skelscope", "Skeletonize the cloud (SkelScope, with clean-up)", "tools.skeletonize",
              lambda: session.start_skeletonize(method="skelscope"), enabled=has_cloud),
            A("study", "Study…", "tools.study", self.open_study, "Ctrl+Shift+S", enabled=can_study),
            A("help", "Keyboard shortcuts", "help", self.show_shortcuts, "F1"),
            A("about", "About SkelScope", "help", self.show_about),
        ]

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
        """The session's questions; the first option is the default (Enter), never a destructive one."""
        if not self.interactive:
            return options[0] if options else None
        item, ok = QtWidgets.QInputDialog.getItem(self, "SkelScope", question, options, 0, False)
        return item if ok else None

    def _ask_index_file(self, title: str) -> str | None:
        if not self.interactive:
            return None
        path, _ = QtWidgets.QFileDialog.getOpenFileName(self, title, self.last_dir(), INDEX_FILTER)
        return path or None

    def open_index_dialog(self) -> None:
        path = self._ask_index_file("Open the skeletal set's index (one cloud row per skeletal point)")
        if path:
            self.session.load_index(path)

    def map_skeleton_dialog(self) -> None:
        """Scale and offset mapping the skeleton into the cloud's frame, filled in with a ``frame``
        warning's suggestion when the shown evaluation has one."""
        from .map_dialog import MapSkeletonDialog, suggested_mapping

        dialog = MapSkeletonDialog(self, suggested_mapping(self.scene.evaluation))
        if dialog.exec() == QtWidgets.QDialog.DialogCode.Accepted:
            self.session.map_skeleton(*dialog.mapping())

    def _confirm_overwrite(self, paths: list[str]) -> bool:
        """True when none of ``paths`` exists or the user agrees to replace those that do (default: no)."""
        existing = [p for p in paths if os.path.exists(p)]
        if not existing:
            return True
        if not self.interactive:
            return False
        names = "\n".join(os.path.basename(p) for p in existing)
        answer = QtWidgets.QMessageBox.question(
            self, "Replace files?", f"These files exist already in {os.path.dirname(existing[0]) or '.'}:\n{names}\n\nReplace them?",
            QtWidgets.QMessageBox.StandardButton.Yes | QtWidgets.QMessageBox.StandardButton.No,
            QtWidgets.QMessageBox.StandardButton.No)
        return answer == QtWidgets.QMessageBox.StandardButton.Yes

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
        paths, _ = QtWidgets.QFileDialog.getOpenFileNames(self, "Open clouds and skeletons", self.last_dir(), FILE_FILTER)
        if paths:
            self.session.load_files(paths)

    def open_as(self, role: str) -> None:
        title = {"cloud": "Open cloud", "skeletal": "Open skeletal point set", "curve": "Open curve skeleton"}[role]
        path, _ = QtWidgets.QFileDialog.getOpenFileName(self, title, self.last_dir(), FILE_FILTER)
        if path:
            self.session.load_as(role, path)

    def recent_files(self) -> list[str]:
        value = self.settings.value("recent_files", [])
        if isinstance(value, str):
            value = [value]
        return [str(v) for v in (value or [])]

    def _add_recent(self, path: str) -> None:
        """The files loaded, newest first: where file dialogs open (File > Recent lists sets and
        sessions, :mod:`skelscope.saved_sessions`)."""
        path = os.path.abspath(path)
        files = [path] + [p for p in self.recent_files() if p != path]
        self.settings.setValue("recent_files", files[:MAX_RECENT])

    @staticmethod
    def _local_paths(event: QtGui.QDropEvent) -> list[str]:
        data = event.mimeData()
        if data is None or not data.hasUrls():
            return []
        return [u.toLocalFile() for u in data.urls() if u.isLocalFile()]

    def _drop_handler(self, paths: list[str]) -> Callable[[list[str]], None] | None:
        """The drop handler that takes ``paths`` (a controller's first), else the loader for their files."""
        for accepts, drop in self._drop_handlers:
            if paths and accepts(paths):
                return drop
        files = [p for p in paths if os.path.isfile(p)]
        folders = [p for p in paths if os.path.isdir(p)]
        if not files and not folders:
            return None

        def load(_paths: list[str]) -> None:
            if folders:  # after the drop: the dialog is modal
                names = ", ".join(os.path.basename(os.path.normpath(p)) for p in folders)
                QtCore.QTimer.singleShot(0, self, lambda: self.show_error(
                    "Could not load", f"{names}: a folder that is not a skelcore compare run (a run's folder holds "
                    "index.json and jobs/): drop its files, or a compare run's folder"))
            if files:
                self.session.load_files(files)

        return load

    def _drag(self, event: QtGui.QDragEnterEvent) -> None:
        if self._drop_handler(self._local_paths(event)) is not None:
            event.acceptProposedAction()
        else:
            event.ignore()

    def _drop(self, event: QtGui.QDropEvent) -> None:
        paths = self._local_paths(event)
        handler = self._drop_handler(paths)
        if handler is None:
            event.ignore()
            return
        event.acceptProposedAction()
        handler(paths)

    dragEnterEvent = _drag  # drops on the panels work too  # noqa: N815
    dragMoveEvent = _drag  # noqa: N815
    dropEvent = _drop  # noqa: N815

    # ---- computing ------------------------------------------------------------------------
    def _task_started(self, name: str) -> None:
        self._set_stage_text(f"{name}: starting…")
        self.progress.setValue(0)
        if self.view.frames_held:
            # An edit's scores on their way: the status bar's task widgets, whose showing lays the bar
            # out on this thread beside the engine's first phase, show after the recoloured frame, as
            # the held repaint would show them (docs/performance.md 6.10). Esc cancels meanwhile.
            QtCore.QTimer.singleShot(0, self, lambda: self.view.after_render(self._task_widgets_after_frame))
        else:
            self._show_task_widgets()
        self._update_actions()
        self._update_no_result()

    def _task_widgets_after_frame(self) -> None:
        QtCore.QTimer.singleShot(0, self, self._show_task_widgets)  # not inside the frame's paint

    def _show_task_widgets(self) -> None:
        """The running task's stage, progress and Cancel button in the status bar (while one runs)."""
        if self.session.runner.running:
            for w in (self.stage, self.progress, self.cancel_button):
                w.setVisible(True)

    def _update_no_result(self) -> None:
        """What the Summary says while it has no result: the evaluation running, cancelled, not run
        yet, or the inputs still to load."""
        from .panels.summary import NO_RESULT

        if self.session.runner.current_name == "evaluation":
            text = "Evaluating… (Esc cancels)"
        elif self.scene.can_evaluate() and self.session.evaluation_cancelled:
            text = "Evaluation cancelled: the inputs are loaded; Evaluate (F5) runs it again."
        elif self.scene.can_evaluate():
            text = "Not evaluated yet: Evaluate (F5)."
        else:
            text = NO_RESULT
        self.summary.set_no_result(text)

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
        self._set_stage_text(stage)

    def _set_stage_text(self, stage: str) -> None:
        """Every stage running side by side (``app.worker.stage_label``), elided to the label's fixed
        width (a status bar that re-lays itself out re-renders the 3D view); the whole in its tooltip."""
        shown = self.stage.fontMetrics().elidedText(stage, QtCore.Qt.TextElideMode.ElideRight, self.stage.width())
        if self.stage.text() != shown or self.stage.toolTip() != stage:
            self.stage.setToolTip(stage)
            self.stage.setText(shown)

    def _task_finished(self, _name: str) -> None:
        self._update_no_result()
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
            if event.kind == "quantities":
                self._plots_stale.add("barcodes")
                self.pick.show_info(None)
                if self.scene.evaluation is None:
                    self.statusBar().clearMessage()  # "evaluation done in …" must not outlive the result
            self._plots_stale.add("histogram")
            self._summary_due = True
            if self.view.frames_held:
                # An edit's scores on their way (or landing): the Summary and the plots follow the
                # recoloured frame, once, not on its path (docs/performance.md 6.10). The actions'
                # states do not wait (Esc cancels the scoring meanwhile).
                self.view.after_render(self._after_frame_panels)
            else:
                self._show_summary()
                self._schedule_plots()
        elif event.kind in ("colouring", "display", "stale"):
            self._plots_stale.add("histogram")
            self._schedule_plots()
        elif event.kind == "layer":
            self.pick.show_info(None)
            names = [os.path.basename(layer.path) + (" (edited)" if layer.edited else "")
                     for layer in self.scene.layers.values() if layer.path]
            if self.scene.curve is not None and self.scene.curve.edited and not self.scene.curve.path:
                names.append("curve (edited)")
            self.setWindowTitle("SkelScope" + (f" — {', '.join(names)}" if names else ""))
            self._update_no_result()
        self._update_actions()

    _summary_due = False  # a scene change the Summary has not shown yet

    def _show_summary(self) -> None:
        if self._summary_due:
            self._summary_due = False
            ev = self.scene.evaluation
            if ev is not None:
                self.summary.set_thresholds(self.scene.beta_star, self.scene.c_star)
            self.summary.show_summary(self.scene.scores(), ev)

    def _after_frame_panels(self) -> None:
        """The panels' part of the scene changes made while the view held its frames, at the event
        loop's next turn after the frame (not inside its paint)."""
        QtCore.QTimer.singleShot(0, self, self._panels_after_frame)

    def _panels_after_frame(self) -> None:
        self._show_summary()
        self._schedule_plots()

    def _prepare_plots(self) -> None:
        """Make the barcode axes while idle (once matplotlib is loaded), not when a result lands."""
        import sys

        if "matplotlib.backends.backend_qtagg" in sys.modules and self.scene.evaluation is None:
            self.barcodes.prepare()
        elif "matplotlib.backends.backend_qtagg" not in sys.modules:
            QtCore.QTimer.singleShot(1000, self, self._prepare_plots)

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

    def _stale_changed(self, reason: str) -> None:
        """Out-of-date results: greyed in the summary, the 3D view and the histogram."""
        self.summary.set_stale(reason)
        self.scene.set_stale(reason)

    def _layer_action(self, action: str, role: str) -> None:
        if action == "close":
            self.session.close_layer(role)
        elif action == "swap":
            self.session.swap_roles()

    def _update_actions(self) -> None:
        self.menus.update()

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
        try:
            params = self.session.params()  # the window's settings and thresholds (beta*, c*)
        except ValueError as exc:
            self.show_error("Study", str(exc))
            return
        dialog = StudyDialog(self, cloud.path, params=params)
        dialog.show()
        self._study_dialog = dialog

    def open_variant(self, cloud: Any, skeletal: Any = None, curve: Any = None, evaluation: Any = None) -> None:
        """Called by the Study dialog: show one variant (arrays, no files) in the 3D view, with its
        stored evaluation when given (shown at once, nothing recomputed)."""
        self.session.show_arrays(cloud, skeletal, curve, evaluation)
        self.view.reset_camera()

    # ---- exports --------------------------------------------------------------------------
    def _shown_evaluation(self) -> Any:
        ev = self.scene.evaluation
        return None if ev is None else with_thresholds(ev, self.scene.beta_star, self.scene.c_star)

    def export_stem(self) -> str:
        """What exports are named after: the loaded cloud's file stem ("skelscope" for in-memory data)."""
        return data_stem(self.scene.input_paths())

    def export_ply(self, out_dir: str, overwrite: bool = False) -> list[str]:
        """``<stem>_skeletal.ply``, ``<stem>_curve.ply``, ``<stem>_curve_samples.ply`` into ``out_dir``;
        an existing file is replaced only with ``overwrite`` (the dialog asks first)."""
        ev = self._shown_evaluation()
        if ev is None:
            raise ValueError("nothing to export: run an evaluation first")
        names = ply_export_names(ev, out_dir, self.export_stem())
        _refuse_existing(names, overwrite)
        # the map of the skeleton layers the shown result was evaluated from (said in the files' header)
        evaluated = self.session._evaluated_layers or (None, self.scene.skeletal, self.scene.curve)
        mappings = {role: getattr(layer, "mapping", None) for role, layer in zip(("skeletal", "curve"), evaluated[1:])}
        return export_coloured_ply(ev, out_dir, self.input_files(), color_by=self.scene.metric, stem=self.export_stem(),
                                   mappings=mappings)

    def export_results(self, prefix: str, overwrite: bool = False) -> list[str]:
        ev = self._shown_evaluation()
        if ev is None:
            raise ValueError("nothing to export: run an evaluation first")
        _refuse_existing(result_export_names(ev, prefix), overwrite)
        return export_results(ev, prefix, self.input_files())

    def save_screenshot(self, path: str, scale: int = 1, transparent: bool = False, colour_bar: bool = True,
                        overwrite: bool = True, background: str | None = None) -> str:
        """The 3D view as PNG, ``scale`` times its size, on a ``background`` of "white", "black" or
        "transparent" (``transparent=True``: the latter)."""
        _refuse_existing([path], overwrite)
        image = self.view.image(scale=scale, transparent=transparent, colour_bar=colour_bar, background=background)
        return write_png(path, image, self.input_files())

    def _guarded(self, what: str, fn: Any, *args: Any, **kwargs: Any) -> Any:
        try:
            out = fn(*args, **kwargs)
        except (ValueError, OSError) as exc:
            self.show_error(f"{what} failed", str(exc))
            return None
        self.show_message(f"{what}: wrote {', '.join(os.path.basename(p) for p in ([out] if isinstance(out, str) else out))}", 8000)
        return out

    def export_ply_dialog(self) -> None:
        folder = QtWidgets.QFileDialog.getExistingDirectory(self, "Export coloured PLY into", self.last_dir())
        ev = self._shown_evaluation()
        if folder and ev is not None and self._confirm_overwrite(ply_export_names(ev, folder, self.export_stem())):
            self._guarded("PLY export", self.export_ply, folder, overwrite=True)

    def export_results_dialog(self) -> None:
        path, _ = QtWidgets.QFileDialog.getSaveFileName(
            self, "Export results (PREFIX.json and PREFIX_*.csv)",
            os.path.join(self.last_dir(), f"{self.export_stem()}_results.json"), "JSON (*.json)",
            options=QtWidgets.QFileDialog.Option.DontConfirmOverwrite)
        ev = self._shown_evaluation()
        if path and ev is not None and self._confirm_overwrite(result_export_names(ev, path)):
            self._guarded("Results export", self.export_results, path, overwrite=True)

    def screenshot_dialog(self) -> None:
        """One dialog: file, scale, background (white, black, transparent), colour bar on or off."""
        from .picture_dialog import PictureDialog

        default = os.path.join(self.last_dir(), f"{self.export_stem()}_{self.scene.metric}.png")
        dialog = PictureDialog(self, default, (self.view.widget.width(), self.view.widget.height()))
        if dialog.exec() != QtWidgets.QDialog.DialogCode.Accepted:
            return
        opts = dialog.options()
        if opts.path and self._confirm_overwrite([opts.path]):
            self._guarded("Picture", self.save_screenshot, opts.path, opts.scale, colour_bar=opts.colour_bar,
                          background=opts.background)

    def save_camera(self, path: str) -> str:
        from .view.camera import save_camera

        return save_camera(path, self.view.camera_state(), self.input_files())

    def load_camera(self, path: str) -> None:
        from .view.camera import load_camera

        self.view.set_camera_state(load_camera(path))

    def save_camera_dialog(self) -> None:
        path, _ = QtWidgets.QFileDialog.getSaveFileName(
            self, "Save camera", os.path.join(self.last_dir(), f"{self.export_stem()}_camera.json"), "Camera (*.json)")
        if path:
            self._guarded("Camera", self.save_camera, path)

    def load_camera_dialog(self) -> None:
        path, _ = QtWidgets.QFileDialog.getOpenFileName(self, "Load camera", self.last_dir(), "Camera (*.json)")
        if path:
            try:
                self.load_camera(path)
            except ValueError as exc:
                self.show_error("Camera", str(exc))

    def showEvent(self, event: QtGui.QShowEvent) -> None:  # noqa: N802
        """The Display | Settings tabs, made on the first show: Qt (6.11) gives the second tab group
        made in a hidden window a second tab bar, drawn over the "Picked element" dock until the event
        loop deletes it, which a script that only calls processEvents never does (the scripted mode;
        tests/app/test_app_layout.py)."""
        if not self._left_tabs_made:
            self._left_tabs_made = True
            self.tabifyDockWidget(self.docks["Display"], self.docks["Settings"])
            self.docks["Settings"].show()
            self.docks["Display"].raise_()
        super().showEvent(event)

    def event(self, event: QtCore.QEvent) -> bool:
        """A tab bar of tabbed docks shows its titles whole, scrolling its tabs when they do not fit: Qt
        elides them ("Barco…", "Def…" in a narrow dock at 1.5 x on 1366 x 768), which hides which
        panel each tab opens. Set when Qt polishes the bar, after its own setup (which sets eliding)."""
        if event.type() == QtCore.QEvent.Type.ChildPolished and isinstance(event.child(), QtWidgets.QTabBar):
            bar = event.child()
            bar.setElideMode(QtCore.Qt.TextElideMode.ElideNone)
            bar.setUsesScrollButtons(True)
        return super().event(event)

    # ---- closing --------------------------------------------------------------------------
    def closeEvent(self, event: QtGui.QCloseEvent) -> None:  # noqa: N802
        """Quitting waits for no work: every task is cancelled and detached (its result can never land;
        an engine child process is killed, a thread stops at its next checkpoint or with the process,
        which leaves by ``os._exit``, see app.__main__), and ``closing`` stops the support still
        computing. Waiting for stale work made Ctrl+Q take up to ``SHUTDOWN_WAIT_S`` longer."""
        self.closing.emit()
        runners = [self.session.runner]
        study = getattr(self, "_study_dialog", None)
        if study is not None:
            runners.append(study.runner)
        for runner in runners:
            runner.discard()
        if study is not None:
            study.hide()  # not close(): its closeEvent would handle its runner again
        self.settings.sync()  # the process may end with os._exit (a task still inside the engine)
        self.view.close()
        super().closeEvent(event)
        if event.isAccepted():
            self._collector_hold.release()


def scrolling(widget: QtWidgets.QWidget, parent: QtWidgets.QWidget) -> QtWidgets.QScrollArea:
    """``widget`` in a frameless scroll area that resizes it: it fills the dock, and scrolls once the
    dock is smaller than the widget's minimum size."""
    area = QtWidgets.QScrollArea(parent)
    area.setWidgetResizable(True)
    area.setFrameShape(QtWidgets.QFrame.Shape.NoFrame)
    area.setWidget(widget)
    return area


_ROLE_TITLES = {"cloud": "cloud", "skeletal": "skeletal point set", "curve": "curve skeleton"}
_STANDARD_VIEWS = (("xy", "Top (XY)"), ("-xy", "Bottom (-XY)"), ("xz", "Front (XZ)"), ("-xz", "Back (-XZ)"),
                   ("yz", "Side (YZ)"), ("-yz", "Other side (-YZ)"), ("iso", "Isometric"))
_STYLES = (("spheres", "Points as shaded spheres", "Shift+S"), ("eye_dome", "Eye-dome lighting", "Shift+E"),
           ("axes", "Orientation axes", "Shift+A"))


def _refuse_existing(paths: list[str], overwrite: bool) -> None:
    """Exports never replace a file without being told to (the dialogs ask first)."""
    if not overwrite:
        existing = [p for p in paths if os.path.exists(p)]
        if existing:
            raise FileExistsError(f"{existing[0]}: exists already (not replaced)")


def _study_available() -> bool:
    import importlib.util

    return importlib.util.find_spec("skelscope.study_dialog") is not None
