"""One picture's 3-D scene on a pyvista plotter: the faint grey cloud, and over it the skeleton,
plain (view "skeleton") or coloured by a local metric (viridis over ``clim``, NaN magenta, docs/metrics.md 5.5)
with an optional colour bar. compare's renders (:mod:`skelcore.compare.render`), ``Evaluation.show``
and ``show_ab`` all build their scenes here, from :func:`skelcore.display.picture_arrays.drawing_arrays`'s dict.

pyvista is imported inside the functions (skelcore never imports plotting at module level).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .. import colors

__all__ = ["SKELETON_VIEW", "add_scene", "metric_values", "metric_lut", "quiet_vtk", "has_nan"]

#: the view without a metric: the skeletal points and the curve in their plain colours
SKELETON_VIEW = "skeleton"


def _unit(rgb: tuple[int, int, int]) -> tuple[float, float, float]:
    return tuple(c / 255 for c in rgb)  # type: ignore[return-value]


def metric_values(arrays: dict[str, np.ndarray], metric: str,
                  prefer: str = "skeletal") -> tuple[np.ndarray, np.ndarray] | None:
    """(points, values) coloured by ``metric``: the skeletal points or the curve (its samples for
    boundedness and centeredness, docs/metrics.md 3; its vertices for smoothness, docs/metrics.md 4), ``prefer``'s first
    when the arrays hold both; None when neither."""
    def skeletal():
        if "skeletal" in arrays:
            return arrays["skeletal"], arrays[f"skeletal_{metric}"]
        return None

    def curve():
        if "curve_vertices" in arrays:
            if metric == "smoothness":
                return arrays["curve_vertices"], arrays["curve_vertex_smoothness"]
            return arrays["curve_samples"], arrays[f"curve_sample_{metric}"]
        return None

    first, second = (skeletal, curve) if prefer == "skeletal" else (curve, skeletal)
    return first() or second()


def has_nan(arrays: dict[str, np.ndarray], metric: str, prefer: str = "skeletal") -> bool:
    """Whether the elements coloured by ``metric`` include an invalid (NaN) one."""
    got = metric_values(arrays, metric, prefer) if metric != SKELETON_VIEW else None
    return got is not None and bool(np.isnan(np.asarray(got[1], float)).any())


def metric_lut(clim: tuple[float, float] = (0.0, 1.0)) -> Any:
    """A pyvista LookupTable of skelcore's metric colour map over ``clim``, NaN magenta (the viewer's)."""
    import pyvista as pv

    lut = pv.LookupTable()
    lut.values = [(int(r), int(g), int(b), 255) for r, g, b in colors.lookup_table(colors.METRIC_COLORMAP, 256)]
    lut.scalar_range = (float(clim[0]), float(clim[1]))
    lut.nan_color = colors.NAN_COLOR
    return lut


def _lines(verts: np.ndarray, edges: np.ndarray) -> Any:
    import pyvista as pv

    edges = np.asarray(edges, np.int64).reshape(-1, 2)
    cells = np.hstack([np.full((len(edges), 1), 2), edges]).astype(np.int64).ravel()
    return pv.PolyData(np.asarray(verts, float), lines=cells)


def quiet_vtk() -> None:
    """VTK logs "bad X server connection" on a machine without X before rendering off-screen fine."""
    try:
        from vtkmodules.vtkCommonCore import vtkLogger

        vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_OFF)
    except (ImportError, AttributeError):  # pragma: no cover
        pass


def _bounds(pts: np.ndarray) -> list[float]:
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    return [lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]]


def add_scene(pl: Any, arrays: dict[str, np.ndarray], view: str, *, prefer: str = "skeletal",
              clim: tuple[float, float] = (0.0, 1.0), colour_bar: bool = False, title: str | None = None,
              point_size: float = 6.0) -> None:
    """Draw ``view`` ("skeleton" or a metric of :data:`skelcore.scores.LOCAL_METRICS`) into the
    plotter's active renderer, framed on the cloud from the iso direction. ``prefer`` picks what a
    metric colours when both skeletons are there ("skeletal" or "curve"); ``colour_bar`` adds the
    bar, titled with the metric, with a NaN swatch when an element is invalid."""
    pl.set_background("white")
    cloud = np.asarray(arrays["cloud"], float)
    pl.add_points(cloud, color=_unit(colors.CLOUD_GREY), point_size=2, opacity=0.35 if view == SKELETON_VIEW else 0.25,
                  render_points_as_spheres=False, reset_camera=False)
    has_curve = "curve_vertices" in arrays and len(arrays.get("curve_edges", ())) > 0
    if view == SKELETON_VIEW:
        if "reference_vertices" in arrays and len(arrays.get("reference_edges", ())):
            # the shape's ground-truth curve: a thin grey line, drawn before (under) the skeleton
            pl.add_mesh(_lines(arrays["reference_vertices"], arrays["reference_edges"]),
                        color=_unit(colors.REFERENCE_COLOR), line_width=1.5, reset_camera=False)
        if "skeletal" in arrays:
            pl.add_points(np.asarray(arrays["skeletal"], float), color=_unit(colors.SKELETAL_COLOR), point_size=4,
                          reset_camera=False)
        if has_curve:
            pl.add_mesh(_lines(arrays["curve_vertices"], arrays["curve_edges"]), color=_unit(colors.CURVE_COLOR),
                        line_width=3, reset_camera=False)
    else:
        got = metric_values(arrays, view, prefer)
        coloured_curve = got is not None and has_curve and got[0] is not arrays.get("skeletal")
        if has_curve and (coloured_curve or "skeletal" not in arrays):
            pl.add_mesh(_lines(arrays["curve_vertices"], arrays["curve_edges"]), color=(0.3, 0.3, 0.3),
                        line_width=1.5 if coloured_curve else 1, lighting=False, reset_camera=False)
        if got is not None and len(got[0]):
            import pyvista as pv

            pts, vals = got
            poly = pv.PolyData(np.asarray(pts, float))
            poly.point_data[view] = np.asarray(vals, float)
            actor = pl.add_mesh(poly, scalars=view, cmap=metric_lut(clim), clim=list(clim), nan_color=colors.NAN_COLOR,
                                style="points", point_size=point_size, render_points_as_spheres=True,
                                lighting=False, show_scalar_bar=False, reset_camera=False)
            if colour_bar:
                pl.add_scalar_bar(title=view, mapper=actor.mapper, n_labels=5, fmt="%.2f", color="black",
                                  vertical=True, position_x=0.86, position_y=0.2, width=0.08, height=0.6,
                                  title_font_size=14, label_font_size=12,
                                  nan_annotation=bool(np.isnan(np.asarray(vals, float)).any()))
    if title:
        pl.add_text(title, position="upper_left", font_size=10, color="black")
    pl.camera_position = "iso"
    pl.reset_camera(bounds=_bounds(cloud))
