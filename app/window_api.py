"""What feature controllers and the scripted mode may use of the main window.

The A/B view (:mod:`skelscope.compare_view`), the comparison-run browser (:mod:`skelscope.compare_run`), the
support views (:mod:`skelscope.support_controller`), saved sessions (:mod:`skelscope.saved_sessions`) and the
scripted mode (:mod:`skelscope.scripted`) type their
window as :class:`WindowApi`, which :class:`skelscope.main_window.MainWindow` implements: they add docks,
menu actions (by named group, :class:`ActionSpec`), drop handlers and display options through it,
and never touch the window's private attributes (``tests/app/test_window_api.py`` walks their code).
A Protocol, not the class, so that no controller imports the window that installs it (no import cycle).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, Protocol, runtime_checkable

from PySide6 import QtCore, QtGui, QtWidgets

if TYPE_CHECKING:
    import numpy as np

    from .scene import Scene
    from .session import Session
    from .view import SceneView

__all__ = ["ActionSpec", "ABComparison", "SessionFiles", "WindowApi", "LEFT", "RIGHT"]

LEFT = QtCore.Qt.DockWidgetArea.LeftDockWidgetArea
RIGHT = QtCore.Qt.DockWidgetArea.RightDockWidgetArea


@dataclass(frozen=True)
class ActionSpec:
    """One menu action, as a row of the window's action table (:data:`skelscope.actions.MENUS` names the groups).

    ``run`` is called with no argument, or with the new state when the action is ``checked``-able;
    ``enabled`` and ``checked`` are read again whenever the scene or a task changes (None: always
    enabled / not checkable). ``name`` is the action's key in ``MainWindow.actions_by_name``.
    """

    name: str
    text: str
    group: str
    run: Callable[..., Any]
    shortcut: str = ""
    enabled: Callable[[], bool] | None = None
    checked: Callable[[], bool] | None = None


class ABComparison(Protocol):
    """The A/B view's controller as the scripted mode and the run browser use it (:mod:`skelscope.compare_view`)."""

    views: list[Any]  # the open A/B windows, newest last

    def open(self, ev_a: Any, ev_b: Any, names: tuple[str, str], thresholds: Any = "window",
             context: str = "") -> Any: ...

    def compare_arrays(self, skeletal: Any, curve: Any, name: str = "B") -> bool: ...


class SessionFiles(Protocol):
    """Saved sessions' controller as the scripted mode uses it (:mod:`skelscope.saved_sessions`)."""

    def open(self, path: str) -> list[str]: ...

    def restore(self, state: Any, path: str) -> list[str]: ...

    def report(self, problems: list[str], name: str) -> None: ...


@runtime_checkable
class WindowApi(Protocol):
    """The main window's public face. Its attributes are read, not replaced (``interactive`` aside)."""

    scene: Scene
    session: Session
    view: SceneView
    compare: ABComparison
    saved_sessions: SessionFiles
    settings: QtCore.QSettings  # the viewer's own settings file (recent entries, ...)
    docks: dict[str, QtWidgets.QDockWidget]
    errors: list[str]  # every error message shown (scripted: recorded instead of shown)
    bug: str | None  # the traceback of an uncaught exception, once one happened
    interactive: bool  # False in the scripted mode: errors are recorded, questions take their default
    element_picked: QtCore.SignalInstance  # (info dict | None): a pick in the 3-D view, after the pick panel
    closing: QtCore.SignalInstance  # the window is about to close

    @property
    def widget(self) -> QtWidgets.QMainWindow:
        """The window as a Qt parent for dialogs, panels and controllers."""
        ...

    def add_dock(self, title: str, widget: QtWidgets.QWidget, area: QtCore.Qt.DockWidgetArea = LEFT,
                 below: str | None = None) -> QtWidgets.QDockWidget: ...

    def add_action(self, spec: ActionSpec) -> QtGui.QAction: ...

    def add_drop_handler(self, accepts: Callable[[list[str]], bool], drop: Callable[[list[str]], None]) -> None: ...

    def submenu(self, group: str) -> QtWidgets.QMenu: ...

    def set_settings(self, params: Any, correspondence: str) -> None: ...

    def picked_element(self) -> dict[str, Any] | None: ...

    def select_element(self, layer: str, location: str, index: int) -> dict[str, Any]: ...

    def add_display_option(self, widget: QtWidgets.QWidget) -> None: ...

    def curve_edits(self) -> dict[str, Any] | None:
        """The edit log of the curve's edits done (None when it is not edited)."""
        ...

    def replay_curve_edits(self, log: dict[str, Any]) -> list[str]:
        """Replay an edit log on the loaded curve as undoable edits; the one-line problems (none: [])."""
        ...

    def last_dir(self) -> str: ...

    def input_files(self) -> tuple[str, ...]: ...

    def pick_element(self, info: dict[str, Any] | None) -> None: ...

    def show_error(self, title: str, message: str, details: str = "") -> None: ...

    def show_message(self, text: str, timeout_ms: int = 8000) -> None: ...

    def report_bug(self, message: str, details: str) -> None: ...

    def open_variant(self, cloud: np.ndarray, skeletal: Any = None, curve: Any = None,
                     evaluation: Any = None) -> None: ...

    def save_screenshot(self, path: str, scale: int = 1, transparent: bool = False, colour_bar: bool = True,
                        overwrite: bool = True, background: str | None = None) -> str: ...

    def close(self) -> bool: ...
