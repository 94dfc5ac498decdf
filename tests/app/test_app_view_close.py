"""The 3D view's close (app/view/scene_view.py ``SceneView.close``): safe to call again, and after
its window was destroyed without being closed."""

from __future__ import annotations

import pytest

pytestmark = pytest.mark.gui


def test_the_view_closes_twice_and_the_window_closes_after_it(window):
    view = window.view
    view.close()
    view.close()  # raised AttributeError on the render window pyvista had let go
    assert view._on_scene not in window.scene._listeners
    assert window.close()  # its closeEvent closes the view once more


def test_the_view_closes_after_its_window_was_destroyed(qtbot, tmp_path):
    import shiboken6
    from PySide6 import QtCore

    from skelscope.main_window import MainWindow

    w = MainWindow(settings=QtCore.QSettings(str(tmp_path / "s.ini"), QtCore.QSettings.Format.IniFormat))
    w.show()
    qtbot.waitExposed(w)
    view, scene = w.view, w.scene
    w.session.runner.shutdown()
    w.deleteLater()
    QtCore.QCoreApplication.sendPostedEvents(None, QtCore.QEvent.Type.DeferredDelete)
    assert not shiboken6.isValid(view.plotter)
    view.close()  # raised RuntimeError on the deleted widget
    view.close()
    assert view._on_scene not in scene._listeners
    scene.clear()  # a scene event reaches no view
