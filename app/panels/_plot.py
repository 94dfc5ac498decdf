"""A side panel with its own matplotlib Figure (no pyplot, no global rc), created on first use:
importing matplotlib's Qt backend costs ~0.4 s, which stays off the viewer's start-up.

Redraws go through :meth:`PlotPanel.request_draw`, a timer, instead of matplotlib's ``draw_idle``,
whose zero-delay call Qt runs straight after the code that changed the plot: making the artists and
drawing them (~20 + ~50 ms) would be one stall of the window instead of two shorter ones. A panel
may also draw its figure in stages, one per event-loop turn (:meth:`PlotPanel._draw_stages`)."""

from __future__ import annotations

import threading
from typing import Any

from PySide6 import QtCore, QtWidgets


def preload_matplotlib() -> None:
    """Import matplotlib in the background (after the first frame), so the first plot is quick."""

    def load() -> None:
        import matplotlib.backends.backend_qtagg  # noqa: F401
        import matplotlib.figure  # noqa: F401

    threading.Thread(target=load, name="skelscope-preload-matplotlib", daemon=True).start()


class PlotPanel(QtWidgets.QWidget):
    drawn = QtCore.Signal()  # after each redraw of the figure

    DRAW_DELAY_MS = 10

    def __init__(self, figsize: tuple[float, float], min_height: int, hint: str,
                 parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__(parent)
        self._figsize = figsize
        self._min_height = min_height
        self._figure: Any = None
        self._canvas: Any = None
        self._layout = QtWidgets.QVBoxLayout(self)
        self._layout.setContentsMargins(2, 2, 2, 2)
        self._hint = QtWidgets.QLabel(hint, self)
        # at the top, a little down: a dock shorter than the plot (a small screen) shows its top
        self._hint.setAlignment(QtCore.Qt.AlignmentFlag.AlignHCenter | QtCore.Qt.AlignmentFlag.AlignTop)
        self._hint.setContentsMargins(0, 24, 0, 0)
        self._hint.setStyleSheet("color: grey")
        self._hint.setWordWrap(True)  # a narrow panel wraps it, never cuts it sideways
        self._hint.setMinimumHeight(min_height)
        self._layout.addWidget(self._hint)
        self._draw_timer = QtCore.QTimer(self)
        self._draw_timer.setSingleShot(True)
        self._draw_timer.setInterval(self.DRAW_DELAY_MS)
        self._draw_timer.timeout.connect(self.draw_now)
        self._stages: tuple[Any, tuple[float, float, float], list[list[Any]]] | None = None
        self._stage_timer = QtCore.QTimer(self)
        self._stage_timer.setSingleShot(True)
        self._stage_timer.setInterval(self.DRAW_DELAY_MS)
        self._stage_timer.timeout.connect(self._draw_stage)

    def request_draw(self) -> None:
        """Redraw the figure in a later event-loop turn (however many changes arrive meanwhile)."""
        self._stages = None  # a redraw in progress is outdated
        if not self._draw_timer.isActive():
            self._draw_timer.start()

    @property
    def draw_pending(self) -> bool:
        return self._draw_timer.isActive() or self._stages is not None

    def _draw_stages(self) -> list[list[Any]] | None:
        """Groups of artists to draw in successive event-loop turns (None: the whole figure in one).
        Each group must be listed in drawing order and the groups must not overlap on screen."""
        return None

    def draw_now(self) -> None:
        self._draw_timer.stop()
        stages = self._draw_stages() if self._canvas is not None else None
        if self._canvas is not None and stages is None:
            self._canvas.draw()  # Agg rendering; the widget repaint follows in Qt's own turn
        elif stages is not None:
            from matplotlib.backends.backend_agg import RendererAgg

            w, h = self._canvas.get_width_height(physical=True)
            # Into a renderer of its own: a repaint between two stages shows the previous figure.
            self._stages = (RendererAgg(w, h, self._figure.dpi), (w, h, self._figure.dpi), list(stages))
            self._draw_stage()
            return
        self.drawn.emit()

    def _draw_stage(self) -> None:
        if self._stages is None:
            return  # a newer request_draw replaced this redraw
        renderer, key, stages = self._stages
        for artist in stages.pop(0):
            artist.draw(renderer)
        if stages:
            self._stage_timer.start()
            return
        self._stages = None
        canvas = self._canvas
        if (*canvas.get_width_height(physical=True), canvas.figure.dpi) != key:
            self.request_draw()  # resized meanwhile
            return
        canvas.renderer, canvas._lastKey = renderer, key  # what FigureCanvasAgg.get_renderer caches
        self._figure.stale = False
        canvas.update()
        self.drawn.emit()

    @property
    def has_figure(self) -> bool:
        return self._figure is not None

    @property
    def figure(self) -> Any:
        if self._figure is None:
            from matplotlib.backends.backend_qtagg import FigureCanvasQTAgg
            from matplotlib.figure import Figure

            self._figure = Figure(figsize=self._figsize, dpi=90)
            self._canvas = FigureCanvasQTAgg(self._figure)
            self._canvas.setMinimumHeight(self._min_height)
            self._layout.removeWidget(self._hint)
            self._hint.hide()
            self._layout.addWidget(self._canvas)
        return self._figure

    @property
    def canvas(self) -> Any:
        self.figure  # noqa: B018 - creates the canvas on first use
        return self._canvas
