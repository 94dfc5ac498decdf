"""The view's single colour bar (which metric the coloured actor shows) and its NaN legend.

pyvista's ``add_scalar_bar`` costs several ms and a new bar re-renders its text, so the bar is made
only when the coloured actor or the metric changes and is otherwise updated in place. The NaN legend
is a magenta swatch with its label to the right of it (never over it, at any size or scale), below
the bar, shown while any shown value is invalid (SPEC 5).
"""

from __future__ import annotations

from typing import Any, Callable

from ..scene import Scene
from .style import MAGENTA

__all__ = ["ColourBar", "BAR_X", "BAR_WIDTH", "NAN_LABEL"]

BAR_X, BAR_Y, BAR_WIDTH, BAR_HEIGHT = 0.87, 0.25, 0.06, 0.5  # normalized viewport
NAN_LABEL = "NaN"  # short: it must fit right of the swatch in a narrow view
_SWATCH = (0.875, 0.18, 0.895, 0.20)  # x0, y0, x1, y1 (normalized viewport)
_TITLE_SIZE, _LABEL_SIZE = 14, 12


class ColourBar:
    """The one scalar bar of ``plotter``, describing the actor last passed to :meth:`update`."""

    def __init__(self, plotter: Any) -> None:
        self.plotter = plotter
        self.actor: Any = None  # the actor the colour bar describes
        self.swatch, self.label = self._make_nan_legend()

    def update(self, actor: Any, scene: Scene) -> None:
        """Describe ``actor`` (None: no bar) coloured by ``scene.metric``; the NaN legend is shown
        while any shown value is invalid."""
        bars = self.plotter.scalar_bars
        if actor is None or actor is not self.actor or scene.metric not in bars:
            for title in list(bars.keys()):
                self.plotter.remove_scalar_bar(title, render=False)
            self.actor = actor
            if actor is None:
                self._show_nan(False)
                return
            self.plotter.add_scalar_bar(
                title=scene.metric, mapper=actor.mapper, n_labels=5, fmt="%.2f", color="black",
                vertical=True, position_x=BAR_X, position_y=BAR_Y, width=BAR_WIDTH, height=BAR_HEIGHT,
                title_font_size=_TITLE_SIZE, label_font_size=_LABEL_SIZE, render=False,
            )
        bar = bars[scene.metric]
        bar.SetLookupTable(actor.mapper.lookup_table)
        bar.SetDrawNanAnnotation(False)
        self._show_nan(scene.n_invalid_shown() > 0)

    @property
    def nan_shown(self) -> bool:
        return bool(self.swatch.GetVisibility())

    def _show_nan(self, on: bool) -> None:
        self.swatch.SetVisibility(on)
        self.label.SetVisibility(on)

    def _make_nan_legend(self) -> tuple[Any, Any]:
        from vtkmodules.vtkCommonCore import vtkPoints  # single modules: `import vtk` loads all of VTK (seconds)
        from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData
        from vtkmodules.vtkRenderingCore import vtkActor2D, vtkCoordinate, vtkPolyDataMapper2D, vtkTextActor

        x0, y0, x1, y1 = _SWATCH
        pts = vtkPoints()
        for x, y in ((x0, y0), (x1, y0), (x1, y1), (x0, y1)):
            pts.InsertNextPoint(x, y, 0.0)
        quad = vtkCellArray()
        quad.InsertNextCell(4, [0, 1, 2, 3])
        poly = vtkPolyData()
        poly.SetPoints(pts)
        poly.SetPolys(quad)
        coord = vtkCoordinate()
        coord.SetCoordinateSystemToNormalizedViewport()
        mapper = vtkPolyDataMapper2D()
        mapper.SetInputData(poly)
        mapper.SetTransformCoordinate(coord)
        swatch = vtkActor2D()
        swatch.SetMapper(mapper)
        swatch.GetProperty().SetColor(*(c / 255.0 for c in MAGENTA))
        label = vtkTextActor()
        label.SetInput(NAN_LABEL)
        prop = label.GetTextProperty()
        prop.SetFontSize(_LABEL_SIZE)
        prop.SetColor(0.0, 0.0, 0.0)
        prop.SetJustificationToLeft()
        prop.SetVerticalJustificationToCentered()
        label.GetPositionCoordinate().SetCoordinateSystemToNormalizedViewport()
        label.SetPosition(x1 + 0.008, (y0 + y1) / 2)  # starts right of the swatch: cannot overlap it
        for a in (swatch, label):
            a.SetVisibility(False)
            self.plotter.renderer.AddViewProp(a)
        return swatch, label

    def label_starts_right_of_swatch(self) -> bool:
        return self.label.GetPosition()[0] > _SWATCH[2]

    def scaled(self, scale: int, visible: bool = True) -> list[Callable[[], None]]:
        """Scale the legend's text by ``scale`` (a scaled screenshot; a text actor keeps its pixel
        size, the bar scales its own) and hide bar and legend
        when not ``visible``; the functions that undo it."""
        undo: list[Callable[[], None]] = []
        bars = list(self.plotter.scalar_bars.values())
        for bar in bars:  # its text already follows the bar's size, which follows the picture's
            on = bar.GetVisibility()
            bar.SetVisibility(on and visible)
            undo.append(lambda b=bar, o=on: b.SetVisibility(o))
        prop = self.label.GetTextProperty()
        size, shown = prop.GetFontSize(), self.nan_shown
        prop.SetFontSize(size * scale)
        self._show_nan(shown and visible)
        undo.append(lambda: (prop.SetFontSize(size), self._show_nan(shown)))
        return undo
