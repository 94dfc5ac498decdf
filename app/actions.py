"""The menu bar as named groups, and the actions placed in them from :class:`ActionSpec` rows.

:data:`MENUS` lists each menu's groups in order ("-" is a separator); the window's own table
(``MainWindow.action_table``) and the feature controllers add actions to a group by its name, never
by a position in a menu, so a new entry cannot shift another one. :meth:`Menus.update` applies every
row's enable and check conditions (after each scene change and task start or end).
"""

from __future__ import annotations

from PySide6 import QtCore, QtGui, QtWidgets

from .window_api import ActionSpec

__all__ = ["MENUS", "SUBMENUS", "Menus"]

MENUS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("&File", ("file.open", "file.session", "file.recent", "file.compare", "file.close", "file.close_all", "-", "file.export", "-",
               "file.quit")),
    ("&Edit", ("edit.history", "-", "edit.mode", "edit.ops")),
    ("&Evaluate", ("evaluate.run", "-", "evaluate.colour")),
    ("&View", ("view.camera", "view.style", "-", "view.camera_files", "-", "view.docks")),
    ("&Tools", ("tools.skeletonize", "tools.study")),
    ("&Help", ("help",)),
)
SUBMENUS = {"file.recent": "Recent", "file.close": "Close"}
"""Groups shown as a submenu of their menu, with this title."""


class Menus:
    """The menu bar built from :data:`MENUS`; ``actions`` maps each added row's name to its QAction."""

    def __init__(self, bar: QtWidgets.QMenuBar, owner: QtWidgets.QWidget) -> None:
        self.owner = owner
        self.actions: dict[str, QtGui.QAction] = {}
        self.specs: dict[str, ActionSpec] = {}
        self.submenus: dict[str, QtWidgets.QMenu] = {}
        self._slots: dict[str, tuple[QtWidgets.QMenu, QtGui.QAction | None]] = {}
        for title, groups in MENUS:
            menu = bar.addMenu(title)
            for group in groups:
                if group == "-":
                    menu.addSeparator()
                elif group in SUBMENUS:
                    sub = menu.addMenu(SUBMENUS[group])
                    self.submenus[group] = sub
                    self._slots[group] = (sub, None)
                else:  # an invisible end marker: the group's actions go just before it
                    end = menu.addSeparator()
                    end.setVisible(False)
                    self._slots[group] = (menu, end)

    def add(self, spec: ActionSpec) -> QtGui.QAction:
        """A QAction for ``spec``, at the end of its group, its shortcut active anywhere in the window."""
        if spec.group not in self._slots:
            raise ValueError(f"no menu group {spec.group!r} (groups: {', '.join(self._slots)})")
        if spec.name in self.actions:
            raise ValueError(f"an action named {spec.name!r} exists already")
        action = QtGui.QAction(spec.text, self.owner)
        if spec.shortcut:
            action.setShortcut(QtGui.QKeySequence(spec.shortcut))
            action.setShortcutContext(QtCore.Qt.ShortcutContext.WindowShortcut)
        if spec.checked is not None:
            action.setCheckable(True)
            action.triggered.connect(spec.run)
        else:
            action.triggered.connect(lambda _checked=False: spec.run())
        self.place(spec.group, action)
        self.owner.addAction(action)
        self.actions[spec.name] = action
        self.specs[spec.name] = spec
        return action

    def place(self, group: str, action: QtGui.QAction) -> None:
        """Put an action made elsewhere (e.g. a dock's toggle) at the end of ``group``."""
        menu, end = self._slots[group]
        if end is None:
            menu.addAction(action)
        else:
            menu.insertAction(end, action)

    def update(self) -> None:
        """Every row's enable condition and checked state, without triggering the actions."""
        for name, spec in self.specs.items():
            action = self.actions[name]
            if spec.enabled is not None:
                action.setEnabled(bool(spec.enabled()))
            if spec.checked is not None:
                on = bool(spec.checked())
                if action.isChecked() != on:
                    action.blockSignals(True)
                    action.setChecked(on)
                    action.blockSignals(False)
