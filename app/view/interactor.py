"""The Qt widget the 3D view draws in, and the input it handles itself.

``ClosingInteractor`` lets go of Qt's GL surface when it closes; ``DropInteractor`` (the main view)
also hands drops to the viewer's loader, reports each painted frame and turns off multisampling under
software GL, timing each. ``ClickFilter`` tells a click (a pick) from a camera drag.
"""

from __future__ import annotations

import time
from typing import Any, Callable

from pyvistaqt import QtInteractor
from PySide6 import QtCore, QtGui

__all__ = ["ClosingInteractor", "DropInteractor", "ClickFilter", "is_software_renderer"]


class ClosingInteractor(QtInteractor):
    """A ``QtInteractor`` that drops its Python handles on Qt's GL context and surface once closed.

    pyvistaqt keeps ``context().surface()`` as a ``QSurface`` wrapper. ``QSurface`` is not a QObject,
    so PySide is never told when Qt deletes it with the widget, and the stale wrapper stays registered
    at the freed address: the next Qt object made there comes back to Python as that ``QSurface``
    (seen in CI: ``QMenu.addSeparator()`` returned a ``QSurface`` in the next window's menu bar).
    A closed view never draws again, so the handles are let go while the C++ objects still live.
    """

    def close(self) -> bool:  # pyvistaqt tears VTK down here and in closeEvent
        result = super().close()
        self._release_gl_handles()
        return result

    def closeEvent(self, event: QtGui.QCloseEvent) -> None:  # noqa: N802
        super().closeEvent(event)
        self._release_gl_handles()

    def _release_gl_handles(self) -> None:
        forget = getattr(self, "_forget_context", None)  # pyvistaqt's reset of _ctx/_surface (its QOpenGLWidget base)
        if forget is not None:
            forget()


class DropInteractor(ClosingInteractor):
    """A ``QtInteractor`` whose drag-and-drop goes to the viewer's loader, not pyvista's reader.

    pyvistaqt's own ``dropEvent`` reads any dropped file with ``pyvista.read`` and adds it as a mesh;
    that would bypass skelcore's loaders and the cloud / skeleton roles, so it is replaced.
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.drop_handler: Callable[[QtGui.QDropEvent], None] | None = None
        self.drag_handler: Callable[[QtGui.QDragEnterEvent], None] | None = None
        self.software_gl: bool | None = None  # known once the GL context exists
        self.on_frame: Callable[[], None] | None = None  # called after each frame is painted
        self.before_frame: Callable[[], None] | None = None  # called right before each frame
        self.frame_seconds = 0.0  # how long the last frame took to paint (render and blit)
        # VTK's interaction (a drag, a release, a key) asks for a repaint instead of rendering at once:
        # a render outside a paint is not shown until the paint that follows it, which rendered again,
        # so every frame it asked for was drawn twice.
        self._painting = False
        iren = self.ren_win.GetInteractor()
        iren.SetEnableRender(False)
        tag = iren.AddObserver("RenderEvent", lambda *_: self._painting or self.update())
        self._vtk_observers.append((iren, tag))  # removed with pyvistaqt's own when the widget closes

    def initializeGL(self) -> None:  # noqa: N802
        super().initializeGL()
        if self.software_gl is None:
            self.software_gl = is_software_renderer(self.ren_win.ReportCapabilities())
            if self.software_gl:
                # pyvista's default 8x MSAA (capped at 4 here) multiplies the fill cost of every
                # frame in a software rasterizer (measured 100 -> 55 ms per frame under llvmpipe);
                # a GPU keeps it.
                self.ren_win.SetMultiSamples(0)
                # order-independent translucency adds its own passes to every frame that holds the
                # translucent cloud (a 100k cloud at opacity 0.35: 100 -> 70 ms per frame under
                # llvmpipe); plain blending of one uniform translucent layer gives the same picture
                # to 2 levels of 255 (docs/performance.md section 5.1).
                renderers = self.ren_win.GetRenderers()
                renderers.InitTraversal()
                for _ in range(renderers.GetNumberOfItems()):
                    renderers.GetNextItem().SetUseOIT(False)

    def paintGL(self) -> None:  # noqa: N802
        if self.before_frame is not None:
            self.before_frame()
        start = time.perf_counter()
        window = getattr(self, "ren_win", None)  # None once closed
        iren = window.GetInteractor() if window is not None else None
        self._painting = True
        if iren is not None:
            iren.SetEnableRender(True)
        try:
            super().paintGL()
        finally:
            if iren is not None:
                iren.SetEnableRender(False)
            self._painting = False
        self.frame_seconds = time.perf_counter() - start
        if self.on_frame is not None:
            self.on_frame()

    def dragEnterEvent(self, event: QtGui.QDragEnterEvent) -> None:  # noqa: N802
        if self.drag_handler is not None:
            self.drag_handler(event)
        else:
            event.ignore()

    def dragMoveEvent(self, event: QtGui.QDragMoveEvent) -> None:  # noqa: N802
        if self.drag_handler is not None:
            self.drag_handler(event)
        else:
            event.ignore()

    def dropEvent(self, event: QtGui.QDropEvent) -> None:  # noqa: N802
        if self.drop_handler is not None:
            self.drop_handler(event)
        else:
            event.ignore()


class ClickFilter(QtCore.QObject):
    """A press and release within a few pixels is a click (a pick); anything else is a drag."""

    def __init__(self, on_click: Callable[[QtCore.QPointF], None]) -> None:
        super().__init__()
        self._on_click = on_click
        self._pressed: QtCore.QPointF | None = None

    def eventFilter(self, obj: QtCore.QObject, event: QtCore.QEvent) -> bool:  # noqa: N802
        t = event.type()
        if t == QtCore.QEvent.Type.MouseButtonPress and event.button() == QtCore.Qt.MouseButton.LeftButton:
            self._pressed = event.position()
        elif t == QtCore.QEvent.Type.MouseButtonRelease and event.button() == QtCore.Qt.MouseButton.LeftButton:
            if self._pressed is not None and (event.position() - self._pressed).manhattanLength() <= 3:
                self._on_click(event.position())
            self._pressed = None
        return False


def is_software_renderer(capabilities: str) -> bool:
    """True when VTK's capability report names a software rasterizer (Mesa llvmpipe / softpipe /
    swrast, SwiftShader, Windows' basic renderer)."""
    for line in capabilities.splitlines():
        if "renderer string" in line.lower():
            name = line.lower()
            return any(s in name for s in ("llvmpipe", "softpipe", "swrast", "software", "swiftshader", "basic render"))
    return False
