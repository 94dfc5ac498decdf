"""The main window's public interface: no module of the viewer but the window itself
touches a private attribute of the window (read from the source with ``ast``), the window implements
:class:`skelscope.window_api.WindowApi`, and actions are placed by menu group from one table."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
WINDOW_NAMES = {"window", "_window", "main_window", "mainwindow"}


def _is_window(node: ast.expr) -> bool:
    """``window``, ``self.window``, ``self._window``, ``x.main_window`` ... : an expression naming the window."""
    if isinstance(node, ast.Name):
        return node.id.lower() in WINDOW_NAMES
    if isinstance(node, ast.Attribute):
        return node.attr.lower() in WINDOW_NAMES
    return False


def private_window_accesses(source: str, filename: str = "<source>") -> list[str]:
    """``file:line window._name`` for every private attribute (one leading underscore, not a dunder)
    read, written or called on an expression naming the window."""
    out = []
    for node in ast.walk(ast.parse(source, filename=filename)):
        if (isinstance(node, ast.Attribute) and node.attr.startswith("_") and not node.attr.startswith("__")
                and _is_window(node.value)):
            out.append(f"{filename}:{node.lineno} {ast.unparse(node)}")
        elif (isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in ("getattr", "setattr")
              and len(node.args) >= 2 and _is_window(node.args[0]) and isinstance(node.args[1], ast.Constant)
              and str(node.args[1].value).startswith("_")):
            out.append(f"{filename}:{node.lineno} {node.func.id}(…, {node.args[1].value!r})")
    return out


def _app_modules() -> list[Path]:
    return [p for p in sorted((ROOT / "app").rglob("*.py")) if p != ROOT / "app" / "main_window.py"]


def test_no_app_module_touches_a_private_attribute_of_the_window():
    assert len(_app_modules()) > 30  # the walk sees the whole package
    found = [hit for p in _app_modules()
             for hit in private_window_accesses(p.read_text(encoding="utf-8"), str(p.relative_to(ROOT)))]
    assert found == []


@pytest.mark.parametrize("code, hits", [
    ("window._dock('x', w)", 1),
    ("self.window._last_dir()", 1),
    ("self._window._inputs", 1),
    ("window._x = 1", 1),
    ("getattr(window, '_last_dir')()", 1),
    ("window.add_dock('x', w); self.window.last_dir(); window.__class__; self._pending; view._actors", 0),
])
def test_the_walk_finds_private_accesses_in_every_form(code, hits):
    assert len(private_window_accesses(code)) == hits


def test_the_walk_fails_on_a_violation_planted_in_a_real_controller():
    source = (ROOT / "app" / "compare_run.py").read_text(encoding="utf-8")
    planted = source.replace("self.window.last_dir()", "self.window._last_dir()")
    assert planted != source and private_window_accesses(source) == []
    assert len(private_window_accesses(planted)) == 1


@pytest.mark.gui
def test_the_window_implements_the_interface_and_controllers_add_actions_by_group(window):
    from PySide6 import QtWidgets

    from skelscope.actions import MENUS
    from skelscope.window_api import ActionSpec, WindowApi

    assert isinstance(window, WindowApi)
    file_menu = window.menuBar().actions()[0].menu()
    texts = [a.text() for a in file_menu.actions() if not a.isSeparator()]
    # the controllers' entries sit in their group, between Recent files and Close, in the order added
    assert texts[texts.index("Recent") + 1: texts.index("Close")] == [
        "Compare with a second skeleton (B)…", "Open comparison run (skelcore compare folder)…"]
    # a new group member lands at the end of its group, whatever was added before
    added = []
    action = window.add_action(ActionSpec("extra", "Extra entry", "file.compare", lambda: added.append(1),
                                          enabled=lambda: window.scene.cloud is not None))
    texts = [a.text() for a in file_menu.actions() if not a.isSeparator()]
    assert texts[texts.index("Close") - 1] == "Extra entry" and window.actions_by_name["extra"] is action
    assert not action.isEnabled()  # its condition is read at once, and again on each scene change
    action.trigger()
    assert added == []
    from skelcore import shapes

    window.scene.set_cloud(shapes.y_shape(300, seed=0).cloud)
    assert action.isEnabled()
    action.trigger()
    assert added == [1]
    with pytest.raises(ValueError, match="no menu group"):
        window.add_action(ActionSpec("other", "Other", "file.nowhere", lambda: None))
    with pytest.raises(ValueError, match="exists already"):
        window.add_action(ActionSpec("extra", "Extra again", "help", lambda: None))
    groups = {g for _, gs in MENUS for g in gs if g != "-"}
    assert {spec.group for spec in window.action_table()} <= groups
    # the support controller's dock sits under "Picked element" and is listed in the View menu
    view_menu = next(a.menu() for a in window.menuBar().actions() if a.text() == "&View")
    assert window.docks["Support"].toggleViewAction() in view_menu.actions()
    assert isinstance(window.widget, QtWidgets.QMainWindow)


@pytest.mark.gui
def test_enable_and_check_conditions_follow_the_scene(window):
    from skelcore import shapes

    a = window.actions_by_name
    assert not a["close_all"].isEnabled() and not a["evaluate"].isEnabled() and not a["export_ply"].isEnabled()
    sh = shapes.y_shape(400, seed=1)
    window.scene.set_cloud(sh.cloud)
    assert a["close_all"].isEnabled() and a["close_cloud"].isEnabled() and not a["close_skeletal"].isEnabled()
    assert a["skeletonize"].isEnabled() and not a["evaluate"].isEnabled()
    window.scene.set_skeletal(sh.skeletal)
    assert a["evaluate"].isEnabled()
    window.scene.set_edges_as_tubes(True)  # changed elsewhere (the Display panel): the menu follows
    assert a["tubes"].isChecked()
    window.scene.set_style("eye_dome", True)
    assert a["style_eye_dome"].isChecked() and not a["style_spheres"].isChecked()
