"""The pictures of one job, as in the paper's graphic table: the skeleton over the cloud, the two H0
barcodes, and the skeleton coloured by boundedness, centeredness and smoothness (viridis, magenta =
invalid, SPEC 5). pyvista renders off-screen and matplotlib draws the barcodes; both are imported
inside the functions (skelcore never imports plotting at module level). PNGs are cached per job key
in ``DIR/renders`` so a rerun redraws nothing.
"""

from __future__ import annotations

import io as _io
import os
from pathlib import Path
from typing import Any

import numpy as np

from .. import colors
from ..io.atomic import atomic_open
from ..scores import LOCAL_METRICS

__all__ = ["VIEWS", "render_job", "draw_barcodes", "barcode_png"]

VIEWS = ("skeleton", "barcodes", *LOCAL_METRICS)
_SIZE = (320, 320)


def _grey(rgb: tuple[int, int, int]) -> tuple[float, float, float]:
    return tuple(c / 255 for c in rgb)  # type: ignore[return-value]


def _metric_values(arrays: dict[str, np.ndarray], metric: str) -> tuple[np.ndarray, np.ndarray] | None:
    """(points, values) to colour: the skeletal points when the job has them, else the curve."""
    if "skeletal" in arrays:
        return arrays["skeletal"], arrays[f"skeletal_{metric}"]
    if "curve_vertices" in arrays:
        if metric == "smoothness":
            return arrays["curve_vertices"], arrays["curve_vertex_smoothness"]
        return arrays["curve_samples"], arrays[f"curve_sample_{metric}"]
    return None


def _lines(verts: np.ndarray, edges: np.ndarray):
    import pyvista as pv

    cells = np.hstack([np.full((len(edges), 1), 2), edges]).astype(np.int64).ravel()
    return pv.PolyData(np.asarray(verts, float), lines=cells)


def _quiet_vtk() -> None:
    """VTK logs "bad X server connection" on a machine without X before rendering off-screen fine."""
    try:
        from vtkmodules.vtkCommonCore import vtkLogger

        vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_OFF)
    except (ImportError, AttributeError):  # pragma: no cover
        pass


def _render_3d(arrays: dict[str, np.ndarray], view: str, size: tuple[int, int]) -> bytes:
    import pyvista as pv

    _quiet_vtk()

    pl = pv.Plotter(off_screen=True, window_size=list(size))
    try:
        pl.set_background("white")
        cloud = np.asarray(arrays["cloud"], float)
        pl.add_points(cloud, color=_grey(colors.CLOUD_GREY), point_size=2, opacity=0.25 if view != "skeleton" else 0.35,
                      render_points_as_spheres=False)
        has_curve = "curve_vertices" in arrays and len(arrays.get("curve_edges", ())) > 0
        if view == "skeleton":
            _add_reference(pl, arrays)
            if "skeletal" in arrays:
                pl.add_points(np.asarray(arrays["skeletal"], float), color=_grey(colors.SKELETAL_COLOR), point_size=4)
            if has_curve:
                pl.add_mesh(_lines(arrays["curve_vertices"], arrays["curve_edges"]), color=_grey(colors.CURVE_COLOR),
                            line_width=3)
        else:
            got = _metric_values(arrays, view)
            if got is not None and len(got[0]):
                pts, vals = got
                rgb = colors.map_to_rgb(np.asarray(vals, float), 0.0, 1.0)
                pl.add_points(np.asarray(pts, float), scalars=rgb, rgb=True, point_size=6,
                              render_points_as_spheres=True)
            if has_curve and "skeletal" not in arrays:
                pl.add_mesh(_lines(arrays["curve_vertices"], arrays["curve_edges"]), color=(0.3, 0.3, 0.3), line_width=1)
        pl.camera_position = "iso"
        pl.reset_camera(bounds=_bounds(cloud))
        img = pl.screenshot(return_img=True)
    finally:
        pl.close()
    return _png(img)


def _add_reference(pl: Any, arrays: dict[str, np.ndarray]) -> None:
    """The shape's reference curve (issue 23), a thin grey line drawn before (under) the skeleton."""
    if "reference_vertices" in arrays and len(arrays.get("reference_edges", ())):
        pl.add_mesh(_lines(arrays["reference_vertices"], arrays["reference_edges"]),
                    color=_grey(colors.REFERENCE_COLOR), line_width=1.5)


def _bounds(pts: np.ndarray) -> list[float]:
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    return [lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]]


def _png(img: np.ndarray) -> bytes:
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib import image as mpimg

    buf = _io.BytesIO()
    mpimg.imsave(buf, np.ascontiguousarray(img), format="png")
    return buf.getvalue()


def draw_barcodes(ax: Any, arrays: dict[str, np.ndarray]) -> None:
    """Both H0 barcodes on one axis: the cloud's (grey) above the skeleton's (blue), the K compared
    bars drawn solid, eps* dashed (paper, Fig. "barcodes"; SPEC 1)."""
    if "cloud_barcode" not in arrays:
        ax.text(0.5, 0.5, "no skeletal points:\nno barcodes", ha="center", va="center", transform=ax.transAxes, fontsize=8)
        ax.set_axis_off()
        return
    k = int(arrays["n_bars"][0])
    eps = float(arrays["eps_star"][0])
    finite_max = 0.0
    for name in ("cloud_barcode", "skeletal_barcode"):
        d = arrays[name][:, 1]
        d = d[np.isfinite(d)]
        finite_max = max(finite_max, float(d.max()) if d.size else 0.0)
    cap = max(finite_max, eps) * 1.1 or 1.0
    rows = 0
    for name, colour, offset in (("cloud_barcode", colors.CLOUD_GREY, 0), ("skeletal_barcode", colors.SKELETAL_COLOR, 1)):
        bars = arrays[name][:k]
        deaths = np.where(np.isfinite(bars[:, 1]), bars[:, 1], cap)
        y = offset * (k + 2) + np.arange(len(bars))
        ax.hlines(y, bars[:, 0], deaths, color=_grey(colour), linewidth=max(0.3, min(2.0, 80 / max(k, 1))))
        rows = max(rows, offset * (k + 2) + len(bars))
    ax.axvline(eps, color="k", linestyle="--", linewidth=0.8)
    ax.set_ylim(rows + 1, -1)
    ax.set_xlim(0, cap)
    ax.set_yticks([k / 2, (k + 2) + k / 2], ["cloud", "skeleton"], fontsize=7)
    ax.tick_params(axis="x", labelsize=6)
    ax.set_xlabel("filtration radius (normalized)", fontsize=7)


def barcode_png(arrays: dict[str, np.ndarray], size: tuple[int, int] = _SIZE) -> bytes:
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    fig = Figure(figsize=(size[0] / 100, size[1] / 100), dpi=100)
    ax = fig.add_subplot(1, 1, 1)
    draw_barcodes(ax, arrays)
    fig.tight_layout()
    buf = _io.BytesIO()
    fig.savefig(buf, format="png")
    return buf.getvalue()


def render_job(out_dir: str | os.PathLike, key: str, arrays: dict[str, np.ndarray],
               size: tuple[int, int] = _SIZE) -> dict[str, Path]:
    """PNG path per view of the job, rendered once (cached in ``out_dir/renders``)."""
    folder = Path(out_dir) / "renders"
    folder.mkdir(exist_ok=True)
    paths = {}
    for view in VIEWS:
        path = folder / f"{key}_{view}.png"
        if not path.exists():
            data = barcode_png(arrays, size) if view == "barcodes" else _render_3d(arrays, view, size)
            with atomic_open(path, "wb") as fh:
                fh.write(data)
        paths[view] = path
    return paths
