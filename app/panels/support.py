"""The picked element's local support as a 2-D plot beside the pick panel (issue 11).

A curve sample's centeredness: its slab's cloud points on the cross-section plane, the ring kept, the
fitted ellipse, its centre and the sample (the paper's figure of the two cutting planes; Eq. 11,
SPEC 3). Boundedness: the covered directions on an equal-area (longitude, z) map with beta (Eq. 5-6;
for the ``paper`` estimator its triangles in the same chart, counted ones filled). A skeletal point's
centeredness: its neighbours and the two centroids of Eq. 10, seen along the line m_s -> m_o.
Lengths are in the user's units.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from PySide6 import QtWidgets

from ..scene.supports import ElementSupport
from ._plot import PlotPanel

SLAB, RING, ELLIPSE, SAMPLE, CENTRE = "#9a9a9a", "#1f4e79", "#d62728", "#ff8c00", "#2ca02c"
COVERED = "#1f4e79"


class SupportPanel(PlotPanel):
    def __init__(self, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__((4.0, 3.2), 220, "pick a skeletal point or a curve sample\n"
                         "to see why its value is what it is", parent)
        self.support: ElementSupport | None = None
        self.title = ""

    def show_support(self, support: ElementSupport | None, scale: float = 1.0) -> None:
        """Draw ``support``; ``scale`` is the evaluation's normalization scale (normalized = user x scale)."""
        self.support = support
        if support is None and not self.has_figure:
            return
        fig = self.figure
        fig.clear()
        ax = fig.add_subplot(1, 1, 1)
        if support is None or (support.kind == "none") or (support.reason and support.detail is None):
            ax.set_axis_off()
            text = "pick a skeletal point or a curve sample" if support is None else support.reason
            ax.text(0.5, 0.5, text, ha="center", va="center", wrap=True, transform=ax.transAxes, color="0.35",
                    fontsize=8)
            self.title = ""
        elif support.kind == "slab":
            self._slab(ax, support, scale)
        elif support.kind == "directions":
            self._directions(ax, support)
        elif support.kind == "knn":
            self._knn(ax, support)
        fig.subplots_adjust(left=0.15, right=0.97, top=0.88, bottom=0.14)
        self.request_draw()

    def _head(self, ax: Any, support: ElementSupport, what: str) -> None:
        self.title = f"{support.element} #{support.index}: {what}"
        ax.set_title(self.title, fontsize=8)
        ax.tick_params(labelsize=7)

    def _slab(self, ax: Any, support: ElementSupport, scale: float) -> None:
        from matplotlib.patches import Ellipse

        sup = support.detail
        flat = sup.flat / scale
        ring = flat[sup.ring]
        self._head(ax, support, f"c = {_fmt(sup.value)}, {len(sup.slab)} slab points, ring {len(sup.ring)}")
        if not len(flat):
            ax.text(0.5, 0.5, support.reason or "empty slab", ha="center", va="center", transform=ax.transAxes,
                    fontsize=8, color="0.35")
            return
        ax.scatter(flat[:, 0], flat[:, 1], s=6, color=SLAB, label="slab", linewidths=0)
        ax.scatter(ring[:, 0], ring[:, 1], s=10, color=RING, label="ring kept", linewidths=0)
        if sup.ellipse is not None:
            centre, axes, angle = sup.ellipse
            ax.add_patch(Ellipse(tuple(np.asarray(centre) / scale), 2 * axes[0] / scale, 2 * axes[1] / scale,
                                 angle=float(np.degrees(angle)), fill=False, color=ELLIPSE, linewidth=1.4,
                                 label="fitted ellipse"))
        if sup.centre is not None:
            c = np.asarray(sup.centre) / scale
            ax.scatter([c[0]], [c[1]], marker="+", s=80, color=CENTRE, label="centre", zorder=5)
        ax.scatter([0.0], [0.0], marker="x", s=50, color=SAMPLE, label="sample", zorder=6)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel("g (cross-section plane)", fontsize=7)
        ax.set_ylabel("h", fontsize=7)
        ax.legend(fontsize=6, frameon=False, loc="upper right", markerscale=0.8)

    def _directions(self, ax: Any, support: ElementSupport) -> None:
        detail = support.detail
        if support.estimator == "paper":
            self._triangles(ax, support)
            return
        lon, z = detail.longitude, detail.z
        dlon, dz = (lon[1] - lon[0]) if len(lon) > 1 else 2 * np.pi, (z[1] - z[0]) if len(z) > 1 else 2.0
        extent = (lon[0] - dlon / 2, lon[-1] + dlon / 2, z[0] - dz / 2, z[-1] + dz / 2)
        from matplotlib.colors import ListedColormap

        ax.imshow(detail.covered.astype(float), origin="lower", extent=np.degrees(extent[:2]).tolist() + list(extent[2:]),
                  aspect="auto", cmap=ListedColormap(["#f4f4f4", COVERED]), vmin=0, vmax=1, interpolation="nearest")
        self._head(ax, support, f"beta = {detail.fraction:.3f} (engine {_fmt(support.value)})")
        ax.set_xlabel("longitude (deg)", fontsize=7)
        ax.set_ylabel("z = sin(latitude)", fontsize=7)

    def _triangles(self, ax: Any, support: ElementSupport) -> None:
        from matplotlib.collections import PolyCollection

        tri = support.detail
        u = tri.directions
        lon = np.degrees(np.arctan2(u[:, 1], u[:, 0]))
        z = u[:, 2]
        polys = np.stack([np.column_stack([lon[t], z[t]]) for t in tri.triangles.T], axis=1)
        # triangles across the seam (longitude jump > 180 deg) would streak over the map
        span = polys[..., 0].max(axis=1) - polys[..., 0].min(axis=1)
        ok = span < 180
        faces = ["#1f4e79" if c else "#f2b8b8" for c in tri.counted[ok]]
        ax.add_collection(PolyCollection(polys[ok], facecolors=faces, edgecolors="white", linewidths=0.2))
        ax.set_xlim(-180, 180)
        ax.set_ylim(-1, 1)
        self._head(ax, support, f"paper: beta = {tri.beta:.3f}, {int(tri.counted.sum())}/{len(tri.counted)} triangles")
        ax.set_xlabel("longitude (deg)", fontsize=7)
        ax.set_ylabel("z = sin(latitude)", fontsize=7)

    def _knn(self, ax: Any, support: ElementSupport) -> None:
        sup = support.detail
        pts = support.points3d
        # the plane of the corresponding cloud points' two main axes (their cross-section), through m_s
        nb = pts["neighbours"]
        cl = pts["cloud"]
        centred = cl - cl.mean(axis=0)
        if len(cl) > 2 and np.linalg.matrix_rank(centred) >= 2:
            g, h = np.linalg.svd(centred, full_matrices=False)[2][:2]
        else:
            g, h = np.eye(3)[0], np.eye(3)[1]
        origin = pts["m_s"][0]

        def flat(p: np.ndarray) -> np.ndarray:
            return np.column_stack([(p - origin) @ g, (p - origin) @ h])

        cloud, skel = flat(pts["cloud"]), flat(nb)
        ax.scatter(cloud[:, 0], cloud[:, 1], s=8, color=SLAB, label="corresponding cloud points", linewidths=0)
        ax.scatter(skel[:, 0], skel[:, 1], s=10, color=RING, label=f"k = {len(nb)} neighbours", linewidths=0)
        mo = flat(pts["m_o"])[0]
        ax.scatter([0.0], [0.0], marker="+", s=80, color=CENTRE, label="m_s (skeletal centroid)", zorder=5)
        ax.scatter([mo[0]], [mo[1]], marker="x", s=60, color=ELLIPSE, label="m_o (cloud centroid)", zorder=6)
        ax.set_aspect("equal", adjustable="datalim")
        self._head(ax, support, f"c = {_fmt(sup.value)} = 1 - |m_o - m_s| / M")
        ax.set_xlabel("main axes of the cloud points", fontsize=7)
        ax.legend(fontsize=6, frameon=False, loc="upper right")


def _fmt(v: float) -> str:
    return "nan" if not np.isfinite(v) else f"{v:.3f}"
