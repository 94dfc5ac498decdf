"""The window's repaints deferred while the view holds its frames for an edit's scores.

The 3D view is a ``QOpenGLWidget``: every repaint of the window, even of one status-bar label,
composes the whole window through GL, under software GL about 11 CPU ms of llvmpipe's threads on both
cores. An edit changes the panels (the Summary emptied, the status bar's stage and progress) while
its first phase runs, which made four such repaints beside the engine's kernels on the same cores
(docs/performance.md 6.10, "The window's repaints held"). While the frames are held, the window's
``UpdateRequest`` events are eaten here and their regions stay dirty; the release asks for one
repaint, and the recoloured frame's own repaint paints them with it, in one composition.
"""

from __future__ import annotations

from typing import Callable

import shiboken6
from PySide6 import QtCore, QtWidgets

__all__ = ["WindowPaintHold"]


class WindowPaintHold(QtCore.QObject):
    """An event filter on a top-level window: its repaints wait while ``held()`` is true;
    :meth:`resume` asks for the one repaint that was deferred, if any."""

    def __init__(self, held: Callable[[], bool]) -> None:
        super().__init__()
        self._held = held
        self._window: QtWidgets.QWidget | None = None
        self.deferred = False  # a repaint of the window was eaten while held

    def watch(self, window: QtWidgets.QWidget) -> None:
        """Filter ``window``'s events (the view's top-level window, known once it is shown)."""
        if window is self._window:
            return
        if self._window is not None:
            self._window.removeEventFilter(self)
        self._window = window
        window.installEventFilter(self)

    def eventFilter(self, obj: QtCore.QObject, event: QtCore.QEvent) -> bool:  # noqa: N802
        if obj is not self._window or event.type() != QtCore.QEvent.Type.UpdateRequest:
            return False
        if self._held():
            self.deferred = True
            return True
        self.deferred = False  # this repaint paints every region dirty so far
        return False

    def resume(self) -> None:
        """The hold is over: the deferred repaint is asked for (Qt asks for none while one it posted
        is outstanding, and the eaten one was)."""
        if self.deferred and self._window is not None:
            self.deferred = False
            QtCore.QCoreApplication.postEvent(self._window, QtCore.QEvent(QtCore.QEvent.Type.UpdateRequest))

    def close(self) -> None:
        """Stop filtering (nothing to undo when the window was destroyed first)."""
        if self._window is not None and shiboken6.isValid(self._window):
            self._window.removeEventFilter(self)
            self._window = None
        self.deferred = False
