"""report.html's defect picture of one job (docs/compare.md "Defects decide"): the cloud in
faint grey, the skeleton in a neutral grey, and on it only the defects the job was warned of, each in
its colour of :data:`skelcore.colors.DEFECT_COLORS`: the missing parts' cloud points (``incomplete``),
the curve's edges on spurious branches, on spurious cycles, outside the shape, on the pieces of a
broken curve (``disconnected``) and on branches along the surface (``along_surface``). The per-element
arrays are the Evaluation's diagnostics (``ev_diag_*`` in the job's npz; docs/diagnostics.md "In the
evaluation"). pyvista is imported inside the renderer (skelcore never imports plotting at module level).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .. import colors
from ..diagnostics.record import DEFECT_BITS
from ..display.plotter import OffscreenPlotter
from ..io.atomic import atomic_open
from .render import SIZE

__all__ = ["DEFECT_VIEW", "DRAWN", "DEFECT_LABELS", "DefectLayers", "defect_layers", "render_defects",
           "legend_html"]

DEFECT_VIEW = "defects"
#: the codes drawn element by element, in drawing order (the widest line first, so that an edge with
#: two defects shows both: a core on a halo)
DRAWN = ("incomplete", "disconnected", "outside", "along_surface", "spurious_cycles", "spurious_branches")
DEFECT_LABELS = {
    "incomplete": "missing parts",
    "disconnected": "pieces of the curve beyond one per piece of the cloud",
    "outside": "edges outside the shape",
    "along_surface": "branches along the surface",
    "spurious_cycles": "spurious cycles",
    "spurious_branches": "spurious branches",
}
_LINE_WIDTH = {"disconnected": 12, "outside": 9, "along_surface": 7, "spurious_cycles": 6, "spurious_branches": 4}


@dataclass
class DefectLayers:
    """What the picture draws: ``missing`` (bool per cloud point), ``edges`` (code -> bool per curve
    edge), ``found`` (the job's defect codes, drawn or not) and ``counts`` (code -> cloud points or
    edges drawn)."""

    found: list[str]
    missing: np.ndarray
    edges: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def counts(self) -> dict[str, int]:
        out = {"incomplete": int(np.count_nonzero(self.missing))} if "incomplete" in self.found else {}
        out.update({c: int(np.count_nonzero(m)) for c, m in self.edges.items()})
        return out


def _edge_bits(arrays: dict[str, np.ndarray], n_edges: int) -> np.ndarray:
    """The defect bits per curve edge; runs stored before ``curve_edge_defects``: an edge has a bit
    when both its vertices have it."""
    bits = arrays.get("ev_diag_curve_edge_defects")
    if bits is not None and len(bits) == n_edges:
        return np.asarray(bits, np.int64)
    vbits = arrays.get("ev_diag_curve_vertex_defects")
    edges = np.asarray(arrays.get("curve_edges", np.zeros((0, 2))), np.int64)
    if vbits is None or not n_edges:
        return np.zeros(n_edges, np.int64)
    vbits = np.asarray(vbits, np.int64)
    return vbits[edges[:, 0]] & vbits[edges[:, 1]]


def defect_layers(arrays: dict[str, np.ndarray], codes: list[str] | set[str]) -> DefectLayers:
    """The elements to draw for the defect codes the job was warned of (``codes``; others ignored).
    The missing parts are the cloud points in a counted region of the skeletal set or of the curve."""
    found = [c for c in sorted(set(codes)) if c in DEFECT_BITS or c in ("frame", "collapse", "missing_cycles")]
    n_cloud = len(arrays["cloud"])
    missing = np.zeros(n_cloud, bool)
    if "incomplete" in found:
        for key in ("ev_diag_cloud_missing_skeletal", "ev_diag_cloud_missing_curve"):
            region = arrays.get(key)
            if region is not None and len(region) == n_cloud:
                missing |= np.asarray(region) >= 0
    edges: dict[str, np.ndarray] = {}
    n_edges = len(arrays.get("curve_edges", ()))
    if n_edges:
        bits = _edge_bits(arrays, n_edges)
        for code in DRAWN[1:]:
            if code in found:
                edges[code] = (bits & DEFECT_BITS[code]) != 0
    return DefectLayers(found=found, missing=missing, edges=edges)


def _rgb(c: tuple[int, int, int]) -> tuple[float, float, float]:
    return tuple(v / 255 for v in c)  # type: ignore[return-value]


def _draw(pl: Any, arrays: dict[str, np.ndarray], layers: DefectLayers) -> None:
    from ..display.scene import _bounds, _lines

    pl.set_background("white")
    cloud = np.asarray(arrays["cloud"], float)
    rest = cloud[~layers.missing]
    if len(rest):
        pl.add_points(rest, color=_rgb(colors.CLOUD_GREY), point_size=2, opacity=0.2,
                      render_points_as_spheres=False, lighting=False)
    if layers.missing.any():
        pl.add_points(cloud[layers.missing], color=_rgb(colors.DEFECT_COLORS["incomplete"]), point_size=5,
                      render_points_as_spheres=False, lighting=False)
    verts = np.asarray(arrays.get("curve_vertices", np.zeros((0, 3))), float)
    edges = np.asarray(arrays.get("curve_edges", np.zeros((0, 2))), np.int64)
    if len(edges):
        pl.add_mesh(_lines(verts, edges), color=_rgb(colors.DEFECT_SKELETON), line_width=2, lighting=False)
        for code in DRAWN[1:]:
            sel = layers.edges.get(code)
            if sel is not None and sel.any():
                pl.add_mesh(_lines(verts, edges[sel]), color=_rgb(colors.DEFECT_COLORS[code]),
                            line_width=_LINE_WIDTH[code], lighting=False)
    elif "skeletal" in arrays and len(arrays["skeletal"]):
        pl.add_points(np.asarray(arrays["skeletal"], float), color=_rgb(colors.DEFECT_SKELETON), point_size=3,
                      render_points_as_spheres=False, lighting=False)
    pl.camera_position = "iso"
    pl.reset_camera(bounds=_bounds(cloud))


def _render(arrays: dict[str, np.ndarray], layers: DefectLayers, size: tuple[int, int],
            plotter: OffscreenPlotter | None = None) -> bytes:
    """The picture's PNG, on ``plotter`` when one of ``size`` is given, else on a plotter of its own."""
    if plotter is not None and plotter.size == tuple(size):
        return plotter.png(lambda pl: _draw(pl, arrays, layers))
    with OffscreenPlotter(size) as own:
        return own.png(lambda pl: _draw(pl, arrays, layers))


def render_defects(out_dir: str | os.PathLike, key: str, arrays: dict[str, np.ndarray], layers: DefectLayers,
                   size: tuple[int, int] = SIZE, plotter: OffscreenPlotter | None = None) -> Path:
    """The job's defect picture, rendered once (cached as ``out_dir/renders/KEY_defects.png``)."""
    folder = Path(out_dir) / "renders"
    folder.mkdir(exist_ok=True)
    path = folder / f"{key}_{DEFECT_VIEW}.png"
    if not path.exists():
        data = _render(arrays, layers, size, plotter)
        with atomic_open(path, "wb") as fh:
            fh.write(data)
    return path


def legend_html(layers: DefectLayers) -> str:
    """A legend naming each style drawn (a swatch, the defect, how many points or edges), then the
    defects found that have no element to draw; "no defect found" for a sound job."""
    import html

    if not layers.found:
        return "<div class=legend><span class=note>no defect found</span></div>"
    counts = layers.counts
    items = []
    for code in DRAWN:
        if code not in layers.found:
            continue
        n = counts.get(code, 0)
        what = "cloud points" if code == "incomplete" else "edges"
        if n:
            items.append(f"<li><span class=swatch style='background:{colors.hex_color(colors.DEFECT_COLORS[code])}'>"
                         f"</span>{html.escape(DEFECT_LABELS[code])}: {n} {what}</li>")
        else:
            items.append(f"<li><span class=swatch></span>{html.escape(code)}: nothing to draw (see the warning)</li>")
    for code in layers.found:
        if code not in DRAWN:
            items.append(f"<li><span class=swatch></span>{html.escape(code)}: not drawn (see the warning)</li>")
    return f"<ul class=legend>{''.join(items)}</ul>"
