"""The view's single colour bar (which metric the coloured actor shows) and its legend of invalid values.

pyvista's ``add_scalar_bar`` costs several ms and a new bar re-renders its text, so the bar is made
only when the coloured actor or the metric changes and is otherwise updated in place; with nothing
coloured it is hidden, not removed (an edit's curve uncoloured until its scores land). The NaN legend
is a magenta swatch labelled "invalid", the word docs/metrics.md 5.5 uses for NaN values, to the right of
it (never over it, at any size or scale), below the bar, shown while any shown value is invalid; in a
view too narrow for the label beside the bar's column, swatch and label move left together until the
label ends inside the view.

The bar's title is a text actor of its own, laid out before every frame from the view's size in
pixels: centred over the bar but never past the view's right edge, its bottom half a label plus a
gap above the bar's top, so it clears the top label ("1.00") in a view of any size. A scaled picture
(VTK's tiles) grows normalized positions and the bar's own text with the scale, but not a plain text
actor's font: the title's and the NaN label's are multiplied by the scale for the picture, so the
layout holds at any scale.
"""

from __future__ import annotations

from typing import Any, Callable

from ..scene import Scene
from .style import MAGENTA

__all__ = ["ColourBar", "BAR_X", "BAR_WIDTH", "NAN_LABEL", "TEXT_COLOURS"]

BAR_X, BAR_Y, BAR_WIDTH, BAR_HEIGHT = 0.87, 0.25, 0.06, 0.5  # normalized viewport
NAN_LABEL = "invalid"  # docs/metrics.md 5.5's word, as in docs/guide/viewer.md
_SWATCH = (0.875, 0.18, 0.895, 0.20)  # x0, y0, x1, y1 (normalized viewport)
_TITLE_SIZE, _LABEL_SIZE = 14, 12
_TITLE_GAP = 4  # pixels between the top label's top and the title's baseline
_RIGHT_MARGIN = 4  # pixels between the title's (and the invalid label's) end and the view's right edge
_LABEL_GAP = 0.008  # normalized viewport between the swatch's right side and its label
TEXT_COLOURS = {"white": (0.0, 0.0, 0.0), "transparent": (0.0, 0.0, 0.0), "black": (1.0, 1.0, 1.0)}
"""The annotations' text colour on each picture background."""


class ColourBar:
    """The one scalar bar of ``plotter``, describing the actor last passed to :meth:`update`."""

    def __init__(self, plotter: Any) -> None:
        self.plotter = plotter
        self.actor: Any = None  # the actor the colour bar describes
        self._nan_shift = 0.0  # how far left of its place the invalid legend is drawn (normalized)
        self.swatch, self.label = self._make_nan_legend()
        self.title = self._make_title()
        self.held = False  # True while the camera moves: the view's size holds, so does the layout
        # laid out right before each render (the view's size is then final)
        plotter.renderer.AddObserver("StartEvent", lambda *_: self.held or self.layout())

    def update(self, actor: Any, scene: Scene) -> None:
        """Describe ``actor`` (None: no bar) coloured by ``scene.metric``; the NaN legend is shown
        while any shown value is invalid."""
        bars = self.plotter.scalar_bars
        if actor is None:  # hidden, kept: an edit's curve is coloured again by the same actor (scene_view.KEPT_ACTORS)
            for bar in bars.values():
                bar.SetVisibility(False)
            self._show_nan(False)
            self.title.SetVisibility(False)
            return
        if actor is not self.actor or scene.metric not in bars:
            for title in list(bars.keys()):
                self.plotter.remove_scalar_bar(title, render=False)
            self.actor = actor
            self.plotter.add_scalar_bar(
                title=scene.metric, mapper=actor.mapper, n_labels=5, fmt="%.2f", color="black",
                vertical=True, position_x=BAR_X, position_y=BAR_Y, width=BAR_WIDTH, height=BAR_HEIGHT,
                title_font_size=_TITLE_SIZE, label_font_size=_LABEL_SIZE, render=False,
            )
            bars[scene.metric].SetTitle("")  # drawn by ``self.title`` (keyed by the metric in pyvista's dict)
            self.title.SetInput(scene.metric)
            self.title.SetVisibility(True)
            self.layout()
        bar = bars[scene.metric]
        bar.SetVisibility(True)
        self.title.SetVisibility(True)
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
        self._swatch_points = pts
        swatch.GetProperty().SetColor(*(c / 255.0 for c in MAGENTA))
        label = vtkTextActor()
        label.SetInput(NAN_LABEL)
        prop = label.GetTextProperty()
        prop.SetFontSize(_LABEL_SIZE)
        prop.SetColor(0.0, 0.0, 0.0)
        prop.SetJustificationToLeft()
        prop.SetVerticalJustificationToCentered()
        label.GetPositionCoordinate().SetCoordinateSystemToNormalizedViewport()
        label.SetPosition(x1 + _LABEL_GAP, (y0 + y1) / 2)  # starts right of the swatch: cannot overlap it
        for a in (swatch, label):
            a.SetVisibility(False)
            self.plotter.renderer.AddViewProp(a)
        return swatch, label

    def _make_title(self) -> Any:
        from vtkmodules.vtkRenderingCore import vtkTextActor

        title = vtkTextActor()
        prop = title.GetTextProperty()
        prop.SetFontSize(_TITLE_SIZE)
        prop.SetColor(0.0, 0.0, 0.0)
        prop.SetVerticalJustificationToBottom()
        title.GetPositionCoordinate().SetCoordinateSystemToNormalizedViewport()
        title.SetVisibility(False)
        self.plotter.renderer.AddViewProp(title)
        return title

    def layout(self) -> None:
        """Place the title from the view's size in pixels: centred over the bar unless that runs past
        the right edge (then it ends just inside it), its bottom above the top label. Skipped while a
        scaled picture renders its tiles: the layout of the view at scale 1 holds (see the module)."""
        ren = self.plotter.renderer
        win = ren.GetRenderWindow()
        if win is None or tuple(win.GetTileScale()) != (1, 1):
            return
        w, h = ren.GetSize()
        if w <= 0 or h <= 0:
            return
        self._place_nan_legend(w)
        if not self.title.GetVisibility():
            return
        size = [0.0, 0.0]
        self.title.GetSize(ren, size)
        centre = BAR_X + BAR_WIDTH / 2
        prop = self.title.GetTextProperty()
        if centre * w + size[0] / 2 > w - _RIGHT_MARGIN:
            prop.SetJustificationToRight()
            x = 1.0 - _RIGHT_MARGIN / w
        else:
            prop.SetJustificationToCentered()
            x = centre
        label_px = self._label_height()
        self.title.SetPosition(x, BAR_Y + BAR_HEIGHT + (label_px / 2 + _TITLE_GAP) / h)

    def _place_nan_legend(self, w: int) -> None:
        """Swatch and label at their place under the bar, or further left by as much as the label
        would run past the view's right edge (``w`` pixels wide)."""
        x0, y0, x1, y1 = _SWATCH
        size = [0.0, 0.0]
        self.label.GetSize(self.plotter.renderer, size)
        end = x1 + _LABEL_GAP + size[0] / w  # the label's right end, normalized
        shift = max(0.0, end - (1.0 - _RIGHT_MARGIN / w))
        shift = min(shift, x0)  # never past the left edge
        if abs(shift - self._nan_shift) < 1e-9:
            return
        self._nan_shift = shift
        for i, (x, y) in enumerate(((x0, y0), (x1, y0), (x1, y1), (x0, y1))):
            self._swatch_points.SetPoint(i, x - shift, y, 0.0)
        self._swatch_points.Modified()
        self.label.SetPosition(x1 - shift + _LABEL_GAP, (y0 + y1) / 2)

    def nan_legend_inside(self) -> bool:
        """The label starts right of the swatch and ends inside the view (for tests)."""
        w = self.plotter.renderer.GetSize()[0]
        size = [0.0, 0.0]
        self.label.GetSize(self.plotter.renderer, size)
        x = float(self.label.GetPosition()[0])
        return self.label_starts_right_of_swatch() and x * w + size[0] <= w

    def _label_height(self) -> float:
        """The bar's label height in pixels (the top label is centred on the bar's top)."""
        bars = list(self.plotter.scalar_bars.values())
        size = bars[0].GetLabelTextProperty().GetFontSize() if bars else _LABEL_SIZE
        return 1.2 * size

    def title_bottom_above_bar(self) -> float:
        """The title's bottom minus the bar's top, in normalized viewport units (for tests)."""
        return float(self.title.GetPosition()[1]) - (BAR_Y + BAR_HEIGHT)

    def label_starts_right_of_swatch(self) -> bool:
        return self.label.GetPosition()[0] > self._swatch_points.GetPoint(1)[0]

    def for_picture(self, scale: int = 1, visible: bool = True, background: str = "white") -> list[Callable[[], None]]:
        """Bar, title and NaN legend for a picture ``scale`` times the view's size: hidden when not
        ``visible``, their text in the background's :data:`TEXT_COLOURS`, the title's and the NaN
        label's fonts ``scale`` times larger (VTK's tiles grow the bar's own text, not theirs); the
        functions that undo it."""
        undo: list[Callable[[], None]] = []
        self.layout()
        for actor in (self.title, self.label):
            prop = actor.GetTextProperty()
            size = prop.GetFontSize()
            prop.SetFontSize(size * int(scale))
            undo.append(lambda p=prop, s=size: p.SetFontSize(s))
        colour = TEXT_COLOURS[background]
        bars = list(self.plotter.scalar_bars.values())
        props = [self.title.GetTextProperty(), self.label.GetTextProperty()]
        for bar in bars:
            on = bar.GetVisibility()
            bar.SetVisibility(on and visible)
            undo.append(lambda b=bar, o=on: b.SetVisibility(o))
            props += [bar.GetLabelTextProperty(), bar.GetTitleTextProperty()]
        for prop in props:
            old = prop.GetColor()
            prop.SetColor(*colour)
            undo.append(lambda p=prop, c=old: p.SetColor(*c))
        title_on, shown = bool(self.title.GetVisibility()), self.nan_shown
        self.title.SetVisibility(title_on and visible)
        self._show_nan(shown and visible)
        undo.append(lambda: (self.title.SetVisibility(title_on), self._show_nan(shown)))
        return undo
