"""Closed 3D views leave no stale Qt wrapper behind (app.view.interactor.ClosingInteractor).

pyvistaqt keeps its GL surface as a ``QSurface`` wrapper, which PySide cannot invalidate when Qt
deletes the widget; the next Qt object allocated at that address came back as the ``QSurface`` (a
CI run failed in ``Menus``: ``addSeparator()`` returned one). Each view must let go of it on close.
"""

from __future__ import annotations

import gc

import pytest
from PySide6 import QtCore, QtGui

from skelcore import evaluate, shapes

pytestmark = pytest.mark.gui


def _surface_wrappers() -> list[object]:
    """The live QSurface wrappers, once the widgets earlier tests left for deferred deletion are gone
    (else one of theirs, counted before, would vanish during the test)."""
    QtCore.QCoreApplication.sendPostedEvents(None, QtCore.QEvent.Type.DeferredDelete)
    gc.collect()
    return [o for o in gc.get_objects() if isinstance(o, QtGui.QSurface)]


def _delete(qtbot, widget) -> None:
    widget.close()
    widget.deleteLater()
    qtbot.waitUntil(lambda: not _alive(widget), timeout=5000)


def _alive(widget) -> bool:
    import shiboken6

    QtCore.QCoreApplication.sendPostedEvents(None, QtCore.QEvent.Type.DeferredDelete)
    return shiboken6.isValid(widget)


def test_a_closed_main_window_holds_no_gl_surface(qtbot, tmp_path):
    from skelscope.main_window import MainWindow

    before = len(_surface_wrappers())
    w = MainWindow(settings=QtCore.QSettings(str(tmp_path / "s.ini"), QtCore.QSettings.Format.IniFormat))
    w.show()
    qtbot.waitExposed(w)
    qtbot.waitUntil(lambda: w.view.plotter._surface is not None, timeout=10000)  # the view drew
    assert len(_surface_wrappers()) == before + 1
    _delete(qtbot, w)
    assert len(_surface_wrappers()) == before


def test_a_closed_ab_view_holds_no_gl_surface(qtbot):
    from skelscope.compare_view import CompareWindow

    sh = shapes.cylinder(800, seed=1)
    ev = evaluate(sh.cloud, sh.skeletal)
    before = len(_surface_wrappers())
    view = CompareWindow(ev, ev, ("a", "b"))
    view.show()
    qtbot.waitExposed(view)
    qtbot.waitUntil(lambda: view.plotter._surface is not None, timeout=10000)
    _delete(qtbot, view)
    assert len(_surface_wrappers()) == before
