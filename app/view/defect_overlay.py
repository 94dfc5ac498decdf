"""The defects drawn over the 3-D view (with a scan's openings and stray points).

Each kind in a style of its own, in :data:`skelcore.colors.DEFECT_COLORS` (on neither colour map, not
magenta): missing parts colour their cloud points; spurious branches and spurious cycles get a wide
translucent halo around their edges (the metric colours stay readable inside it); curve edges outside
the shape are dashed; openings are their boundary loops (each rim followed along its points, never a
chord longer than a few spacings); stray points are large dark-red points. The selected defect (the
Defects panel's row) or branch (a click on the curve) is redrawn in the pick colour. A legend of the
styles shown sits in the view's bottom right (the support legend holds the top left, the colour bar
the right, the axes the bottom left), its box sized from its text in points at the window's DPI, so
it grows with Qt's scale factor as the colour bar's labels do. Actors are named ``defect-*``; only this module draws them.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pyvista as pv

from skelcore.colors import DEFECT_COLORS, PICK_COLOR

from ..scene.defects import DefectRow, opening_path
from .actors import display_coordinates, draw_in_front
from .lod import lod_indices
from .style import greyed

__all__ = ["DefectOverlay", "LEGEND_LABELS", "STYLES", "defect_legend", "fit_legend", "LEGEND_FONT_PT"]

#: per drawn set: (style, legend label)
STYLES: dict[str, tuple[str, str]] = {
    "incomplete": ("points", "missing part (cloud points)"),
    "spurious_branches": ("halo", "spurious branch"),
    "spurious_cycles": ("halo", "spurious cycle"),
    "outside": ("dashes", "edge outside the shape"),
    "disconnected": ("halo", "broken curve (extra piece)"),
    "along_surface": ("halo", "branch along the surface"),
    "open_surface": ("loop", "opening (boundary loop)"),
    "outliers": ("large points", "stray point (outlier)"),
    "selected": ("halo", "selected (defect or branch)"),
}
LEGEND_LABELS = {key: label for key, (_style, label) in STYLES.items()}
HALO_WIDTH, SELECTED_WIDTH, DASH_WIDTH, LOOP_WIDTH = 11.0, 14.0, 5.0, 3.0
MAX_DRAWN = 300_000  # at most this many missing-part points drawn (an even subsample beyond)
DASHES_PER_EDGE = 4  # each outside edge drawn as this many dashes with gaps between
LEGEND_FONT_PT = 10
"""The legend's text in points. VTK turns points into pixels at the render window's DPI (72 x the
device pixel ratio, set by pyvistaqt), as for the colour bar's labels, so the legend grows with Qt's
scale factor; a legend box sized as a share of the view fitted its text to the box instead (7 pixels
at QT_SCALE_FACTOR 1.5 on a 1366 x 768 screen)."""
LEGEND_ENTRY = 1.6  # an entry's height per line of text (the symbol is as tall)
LEGEND_PAD = 3  # vtkLegendBoxActor's padding, pixels at 72 DPI
LEGEND_MARGIN = 0.01  # normalized viewport between the box and the view's right and bottom edges


def _segments(points: np.ndarray, pairs: np.ndarray) -> pv.PolyData:
    pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
    cells = np.hstack([np.full((len(pairs), 1), 2, dtype=np.int64), pairs]).ravel()
    return pv.PolyData(display_coordinates(points), lines=cells)


def dashed(vertices: np.ndarray, edges: np.ndarray, dashes: int = DASHES_PER_EDGE) -> pv.PolyData:
    """Each edge cut into ``2 * dashes - 1`` equal parts, every other one kept: a dashed line (VTK's
    OpenGL2 backend has no line stipple)."""
    v = np.asarray(vertices, dtype=float)
    e = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    parts = 2 * dashes - 1
    t = np.arange(0, parts, 2)  # start of each kept part
    a, b = v[e[:, 0]], v[e[:, 1]]
    starts = a[:, None, :] + (b - a)[:, None, :] * (t / parts)[None, :, None]
    ends = a[:, None, :] + (b - a)[:, None, :] * ((t + 1) / parts)[None, :, None]
    pts = np.stack([starts, ends], axis=2).reshape(-1, 3)
    return _segments(pts, np.arange(len(pts)).reshape(-1, 2))


def legend_face(style: str) -> pv.PolyData:
    """The legend's symbol of a style: a thick bar (halo), two dashes, a ring (loop), a disc (points)."""
    from pyvista.plotting.renderer import make_legend_face

    if style == "halo":
        return make_legend_face(pv.Rectangle().scale((1.0, 0.45, 1.0)))
    if style == "dashes":
        pts = np.array([[0, 0, 0], [0.4, 0, 0], [0.4, 0.15, 0], [0, 0.15, 0],
                        [0.6, 0, 0], [1.0, 0, 0], [1.0, 0.15, 0], [0.6, 0.15, 0]], dtype=float)
        return make_legend_face(pv.PolyData(pts, faces=[4, 0, 1, 2, 3, 4, 4, 5, 6, 7]))
    if style == "loop":
        return make_legend_face(pv.Disc(inner=0.3, outer=0.5, c_res=24))
    return make_legend_face("circle")


def defect_legend(keys: list[str], stale: bool = False) -> Any:
    """The legend of the drawn defect styles ``keys`` (of :data:`STYLES`), in the view's bottom right: a
    vtkLegendBoxActor for a renderer's ``AddViewProp`` (the main view's and each half of the A/B view's)."""
    from vtkmodules.vtkRenderingAnnotation import vtkLegendBoxActor

    legend = vtkLegendBoxActor()
    legend.SetNumberOfEntries(len(keys))
    for i, key in enumerate(keys):
        style, label = STYLES[key]
        face = legend_face(style)
        # the symbol carries its colour as scalars; the entry's colour (the text's) stays black
        colour = DEFECT_COLORS.get(key, PICK_COLOR)
        colour = greyed(colour) if stale else colour
        face.point_data.set_array(np.tile(np.asarray(colour, np.uint8), (face.n_points, 1)), "rgb")
        face.point_data.active_scalars_name = "rgb"
        legend.SetEntry(i, face, label, [0.0, 0.0, 0.0])
    legend.ScalarVisibilityOn()
    legend.UseBackgroundOn()
    legend.SetBackgroundColor(0.925, 0.925, 0.925)
    legend.BorderOn()
    height = 0.035 * len(keys)
    legend.GetPositionCoordinate().SetCoordinateSystemToNormalizedViewport()
    legend.GetPositionCoordinate().SetValue(0.70, 0.01)
    legend.GetPosition2Coordinate().SetCoordinateSystemToNormalizedViewport()
    legend.GetPosition2Coordinate().SetValue(0.29, height)
    legend.GetEntryTextProperty().SetColor(0, 0, 0)
    return legend


def fit_legend(legend: Any, renderer: Any, labels: list[str]) -> bool:
    """Size ``legend``'s box in pixels from its ``labels`` at :data:`LEGEND_FONT_PT` and the window's
    DPI, in the bottom right of ``renderer``'s viewport; a view too small for it shrinks the whole box
    (to 98 % of the width, 60 % of the height). Skipped while a scaled picture renders its tiles (the
    box, in normalized coordinates, grows with the picture). Whether the box was placed."""
    from vtkmodules.vtkRenderingCore import vtkTextProperty, vtkTextRenderer

    win = renderer.GetRenderWindow()
    w, h = renderer.GetSize()
    if win is None or w <= 0 or h <= 0 or not labels or tuple(win.GetTileScale()) != (1, 1):
        return False
    dpi = int(win.GetDPI())
    prop = vtkTextProperty()
    prop.SetFontSize(LEGEND_FONT_PT)
    text = vtkTextRenderer.GetInstance()
    widths, line = [], 1
    for label in labels:
        box = [0, 0, 0, 0]
        text.GetBoundingBox(prop, label, box, dpi)
        widths.append(box[1] - box[0] + 1)
        line = max(line, box[3] - box[2] + 1)
    pad = LEGEND_PAD * dpi / 72
    entry = LEGEND_ENTRY * line
    width = max(widths) + entry + 4 * pad  # symbol, text and the paddings between and around them
    height = len(labels) * entry + 2 * pad
    shrink = min(1.0, 0.98 * w / width, 0.6 * h / height)
    width, height = width * shrink / w, height * shrink / h
    legend.GetPositionCoordinate().SetValue(max(0.0, 1.0 - LEGEND_MARGIN - width), LEGEND_MARGIN)
    legend.GetPosition2Coordinate().SetValue(width, height)
    legend.SetPadding(max(1, round(pad)))
    return True


def keep_fitted(legend: Any, renderer: Any, labels: list[str]) -> int:
    """Fit ``legend`` now and before every frame of ``renderer`` whose size or DPI changed (a
    resized view, a window moved to another screen); the observer's tag, to remove it with the legend."""
    last: list[tuple[int, int, int]] = []

    def fit(*_: Any) -> None:
        win = renderer.GetRenderWindow()
        key = (*renderer.GetSize(), int(win.GetDPI()) if win is not None else 0)
        if last and last[0] == key:
            return
        if fit_legend(legend, renderer, labels):
            last[:] = [key]

    fit()
    return int(renderer.AddObserver("StartEvent", fit))


class DefectOverlay:
    """Draws :class:`~skelscope.scene.defects.DefectRow` geometry into a :class:`~skelscope.view.SceneView`'s plotter."""

    def __init__(self, view: Any) -> None:
        self.view = view
        self.names: list[str] = []
        self.shown: list[str] = []  # the drawn sets' keys (STYLES), in legend order
        self.legend: Any = None
        self._legend_observer = 0  # the renderer's observer that keeps the legend fitted (keep_fitted)
        self._selected: list[str] = []
        self.stale = False

    @property
    def plotter(self) -> Any:
        return self.view.plotter

    def clear(self) -> None:
        """Remove every drawn set; a frame only when something was drawn (an edit's first phase clears
        an empty overlay after its recoloured frame: no second frame for it)."""
        drawn = bool(self.names or self._selected or self.legend is not None)
        self.clear_selected()
        for name in self.names:
            self.plotter.remove_actor(name, render=False)
        self.names, self.shown = [], []
        self._set_legend()
        if drawn:
            self.view.request_render()

    def show(self, ev: Any, rows: list[DefectRow], cloud_size: float = 2.0, stale: bool = False) -> None:
        """Draw every row of ``rows`` (the defects of ``ev``) by kind; ``stale``: washed toward grey, as the
        metric colours of out-of-date results are."""
        self.clear()
        self.stale = stale
        colours = {k: greyed(c) if stale else c for k, c in DEFECT_COLORS.items()}
        if ev is None or not rows:
            return
        cloud = None if getattr(ev, "cloud", None) is None else np.asarray(ev.cloud, dtype=float)
        curve = None if getattr(ev, "curve", None) is None else ev.curve.curve
        by_code: dict[str, list[DefectRow]] = {}
        for row in rows:
            by_code.setdefault(row.code, []).append(row)
        # missing parts: their cloud points, a little larger than the cloud's, in front of it
        rows_missing = [r.cloud_rows for r in by_code.get("incomplete", []) if len(r.cloud_rows)]
        if rows_missing and cloud is not None:
            sel = np.unique(np.concatenate(rows_missing))
            if len(sel) > MAX_DRAWN:  # a frame of millions more points costs seconds in software GL
                sel = sel[lod_indices(len(sel), MAX_DRAWN)]
            self._points("incomplete", cloud[sel], colours["incomplete"], cloud_size + 2.0, offset=-100.0)
        if curve is not None:
            verts = np.asarray(curve.vertices, dtype=float)
            edges = np.asarray(curve.edges, dtype=np.int64).reshape(-1, 2)
            for code in ("spurious_branches", "spurious_cycles", "disconnected", "along_surface"):
                ids = [r.edges for r in by_code.get(code, []) if len(r.edges)]
                if ids:
                    self._lines(code, _segments(verts, edges[np.unique(np.concatenate(ids))]), colours[code],
                                HALO_WIDTH, opacity=0.45, offset=-150.0)
            ids = [r.edges for r in by_code.get("outside", []) if len(r.edges)]
            if ids:
                self._lines("outside", dashed(verts, edges[np.unique(np.concatenate(ids))]), colours["outside"],
                            DASH_WIDTH, offset=-500.0)
        openings = [o for o in (getattr(getattr(ev, "scan", None), "openings", None) or [])]
        if openings and cloud is not None:
            pts, pairs = [], []
            start = 0
            for o in openings:
                sel = np.asarray(o.get("rows") or [], dtype=np.int64)
                if len(sel) < 3 or sel.max() >= len(cloud):
                    continue
                verts, segs = opening_path(cloud[sel])
                pts.append(verts)
                pairs.append(segs + start)
                start += len(verts)
            if pts:
                self._lines("open_surface", _segments(np.vstack(pts), np.vstack(pairs)), colours["open_surface"],
                            LOOP_WIDTH, offset=-300.0)
        stray = [r.points for r in by_code.get("outliers", []) if len(r.points)]
        if stray:
            self._points("outliers", np.vstack(stray), colours["outliers"], 12.0, spheres=True, offset=-300.0)
        self._set_legend()
        self.view.request_render()

    def select(self, ev: Any, row: DefectRow | None, cloud_size: float = 2.0) -> None:
        """Redraw one defect (or a clicked branch, as a row with its edges) in the pick colour."""
        self.clear_selected()
        if row is None or ev is None:
            self.view.request_render()
            return
        curve = None if getattr(ev, "curve", None) is None else ev.curve.curve
        if curve is not None and len(row.edges):
            edges = np.asarray(curve.edges, dtype=np.int64).reshape(-1, 2)[row.edges]
            self._lines("selected", _segments(np.asarray(curve.vertices, float), edges), PICK_COLOR, SELECTED_WIDTH,
                        offset=-160.0, selected=True)
        elif len(row.points) and not (row.code == "thin_parts" and not len(row.cloud_rows)):  # a box: framed only
            size = 12.0 if row.code == "outliers" else (cloud_size + 3.0 if len(row.cloud_rows) else 9.0)
            self._points("selected", row.points, PICK_COLOR, size, offset=-350.0, selected=True)
        self._set_legend()
        self.view.request_render()

    def clear_selected(self) -> None:
        for name in self._selected:
            self.plotter.remove_actor(name, render=False)
            if name in self.names:
                self.names.remove(name)
        if self._selected and "selected" in self.shown:
            self.shown.remove("selected")
            self._set_legend()
        self._selected = []

    def set_visible(self, on: bool) -> None:
        """Show or hide the drawn sets and their legend; a frame only when one of them changes."""
        changed = False
        for name in self.names:
            actor = self.plotter.actors.get(name)
            if actor is not None and bool(actor.GetVisibility()) != bool(on):
                actor.SetVisibility(on)
                changed = True
        if self.legend is not None and bool(self.legend.GetVisibility()) != (on and bool(self.shown)):
            self.legend.SetVisibility(on and bool(self.shown))
            changed = True
        if changed:
            self.view.request_render()

    # ---- drawing --------------------------------------------------------------------------
    def _points(self, key: str, points: np.ndarray, colour: Any, size: float, spheres: bool = False,
                offset: float = -300.0, legend: bool = True, selected: bool = False) -> None:
        name = f"defect-{key}"
        actor = self.plotter.add_mesh(pv.PolyData(display_coordinates(points)), color=colour, style="points",
                                      point_size=size, lighting=False, render_points_as_spheres=spheres, name=name,
                                      reset_camera=False, render=False, pickable=False)
        draw_in_front(actor, offset)
        self._added(name, key, legend, selected)

    def _lines(self, key: str, mesh: pv.PolyData, colour: Any, width: float, opacity: float = 1.0,
               offset: float = -300.0, legend: bool = True, selected: bool = False) -> None:
        name = f"defect-{key}"
        actor = self.plotter.add_mesh(mesh, color=colour, style="wireframe", line_width=width, opacity=opacity,
                                      lighting=False, name=name, reset_camera=False, render=False, pickable=False)
        draw_in_front(actor, offset)
        self._added(name, key, legend, selected)

    def _added(self, name: str, key: str, legend: bool, selected: bool) -> None:
        self.names.append(name)
        if selected:
            self._selected.append(name)
        if legend:
            self.shown.append(key)

    def _set_legend(self) -> None:
        """One legend entry per drawn style (a vtkLegendBoxActor of its own: pyvista's one legend is the
        support overlay's)."""
        if self.legend is not None:
            self.plotter.renderer.RemoveViewProp(self.legend)
            self.plotter.renderer.RemoveObserver(self._legend_observer)
            self.legend = None
        if not self.shown:
            return
        legend = defect_legend(self.shown, self.stale)
        self.plotter.renderer.AddViewProp(legend)
        self._legend_observer = keep_fitted(legend, self.plotter.renderer, self.legend_labels)
        self.legend = legend

    @property
    def legend_labels(self) -> list[str]:
        """The legend's entries (what a test or a screenshot reader checks)."""
        return [STYLES[key][1] for key in self.shown]
