"""The picked element's local support as a 2-D plot beside the pick panel.

A curve sample's centeredness: its slab's cloud points on the cross-section plane, the ring kept, the
fitted ellipse, its centre and the sample (the paper's figure of the two cutting planes; Eq. 11,
docs/metrics.md 3). Boundedness: the covered directions on an equal-area (longitude, z) map with beta (Eq. 5-6;
for the ``paper`` estimator its triangles in the same chart, counted ones filled) and, beside it, on a
small 3-D sphere. A skeletal point's
centeredness: its neighbours and the two centroids of Eq. 10, seen along the line m_s -> m_o.
Smoothness: a skeletal point's tangent and its neighbours' tangents with each one's score
|1 - 2 theta / pi| (Eq. 13-14), the one setting the value marked; a curve vertex's two edges and
their angle (Eq. 15). Lengths are in the user's units. Colours are the 3-D overlay's
(:data:`skelcore.colors.SUPPORT_COLORS`); legends sit beside the plot, never on its data.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from PySide6 import QtWidgets

from skelcore.colors import PICK_COLOR, SUPPORT_COLORS, hex_color
from skelcore.scores import format_score

from ..scene.supports import ElementSupport
from ._plot import PlotPanel

SLAB, RING, ELLIPSE, CENTRE, M_O = (hex_color(SUPPORT_COLORS[k]) for k in ("slab", "ring", "ellipse", "centre", "m_o"))
SAMPLE = hex_color(PICK_COLOR)  # the picked element, as its 3-D marker
COVERED = "#1f4e79"
#: right edge of the axes when a legend sits beside them
_LEGEND_RIGHT = 0.60


class SupportPanel(PlotPanel):
    def __init__(self, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__((4.0, 3.2), 220, "pick a skeletal point or a curve sample\n"
                         "to see why its value is what it is", parent)
        self.support: ElementSupport | None = None
        self.title = ""
        self.sphere_faces: tuple[np.ndarray, np.ndarray] | None = None  # boundedness: (centres, covered)

    def show_support(self, support: ElementSupport | None, scale: float = 1.0) -> None:
        """Draw ``support``; ``scale`` is the evaluation's normalization scale (normalized = user x scale)."""
        self.support = support
        self.sphere_faces = None
        if support is None and not self.has_figure:
            return
        fig = self.figure
        fig.clear()
        ax = fig.add_subplot(1, 1, 1)
        if support is None or (support.kind == "none") or (support.reason and support.detail is None):
            ax.set_axis_off()
            text = "pick a skeletal point or a curve sample" if support is None else support.reason
            # at the top: a dock shorter than the plot (a small screen) shows its top, not its middle
            ax.text(0.5, 1.0, text, ha="center", va="top", wrap=True, transform=ax.transAxes, color="0.35",
                    fontsize=8)
            self.title = ""
        elif support.kind == "slab":
            self._slab(ax, support, scale)
        elif support.kind == "directions":
            fig.clear()  # the map and, beside it, the same directions on a small 3-D sphere
            grid = fig.add_gridspec(1, 2, width_ratios=[1.45, 1.0], wspace=0.08)
            chart = fig.add_subplot(grid[0])
            self._directions(chart, support)
            chart.set_title("")
            fig.suptitle(self.title, fontsize=8, y=0.98)  # over both: the map alone is too narrow for it
            self._sphere(fig.add_subplot(grid[1], projection="3d"), support)
        elif support.kind == "knn":
            self._knn(ax, support)
        elif support.kind == "smoothness":
            self._smoothness(ax, support)
        beside = ax.get_legend() is not None and support is not None and support.kind in ("slab", "knn", "smoothness")
        fig.subplots_adjust(left=0.15, right=_LEGEND_RIGHT if beside else 0.97, top=0.88, bottom=0.14)
        self.request_draw()

    @staticmethod
    def _legend(ax: Any) -> None:
        """The legend beside the axes (not over the slab, where it would hide the ring's points)."""
        ax.legend(fontsize=6, frameon=False, loc="upper left", bbox_to_anchor=(1.03, 1.0), borderaxespad=0.0,
                  markerscale=0.8)

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
        self._legend(ax)

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

    def _sphere(self, ax: Any, support: ElementSupport) -> None:
        """The map's directions on the unit sphere (world axes, z up): the raster's cells (equal area)
        or the paper estimator's triangles, covered / counted ones in blue. ``sphere_faces`` keeps
        each face's centre and whether it is covered, as drawn."""
        from mpl_toolkits.mplot3d.art3d import Poly3DCollection

        detail = support.detail
        if support.estimator == "paper":
            polys = detail.directions[detail.triangles]  # (t, 3, 3)
            covered = np.asarray(detail.counted, dtype=bool)
            colours = np.where(covered[:, None], _rgba(COVERED), _rgba("#f2b8b8"))
        else:
            rows, bins = detail.covered.shape
            z = np.linspace(-1.0, 1.0, rows + 1)
            lon = np.linspace(-np.pi, np.pi, bins + 1)
            r = np.sqrt(np.clip(1.0 - z * z, 0.0, None))
            corner = np.stack([r[:, None] * np.cos(lon)[None], r[:, None] * np.sin(lon)[None],
                               np.repeat(z[:, None], bins + 1, axis=1)], axis=-1)  # (rows+1, bins+1, 3)
            polys = np.stack([corner[:-1, :-1], corner[:-1, 1:], corner[1:, 1:], corner[1:, :-1]], axis=2)
            polys = polys.reshape(-1, 4, 3)
            covered = detail.covered.reshape(-1)
            colours = np.where(covered[:, None], _rgba(COVERED), _rgba("#f4f4f4"))
        centres = polys.mean(axis=1)
        centres /= np.linalg.norm(centres, axis=1, keepdims=True)
        self.sphere_faces = (centres, covered)
        # look at the covered side (its mean direction), the z axis kept vertical
        mean = centres[covered].mean(axis=0) if covered.any() else np.zeros(3)
        if np.linalg.norm(mean) > 0.2:
            elev = float(np.clip(np.arcsin(np.clip(mean[2] / np.linalg.norm(mean), -1, 1)), -1.1, 1.1))
            azim = float(np.arctan2(mean[1], mean[0])) if np.hypot(mean[0], mean[1]) > 1e-6 else np.radians(-60.0)
        else:
            elev, azim = np.radians(20.0), np.radians(-60.0)
        eye = np.array([np.cos(elev) * np.cos(azim), np.cos(elev) * np.sin(azim), np.sin(elev)])
        light = eye + np.array([0.0, 0.0, 0.6])
        shade = 0.5 + 0.5 * np.clip(centres @ (light / np.linalg.norm(light)), 0.0, 1.0)  # Lambert, so it reads round
        colours = colours.copy()
        colours[:, :3] *= shade[:, None]
        # edges in the face's colour close the hairline gaps antialiasing leaves between faces
        ax.add_collection3d(Poly3DCollection(list(polys), facecolors=colours, edgecolors=colours, linewidths=0.3))
        t = np.linspace(0, 2 * np.pi, 97)
        for z0 in ((-0.5, 0.0, 0.5) if support.estimator == "paper" else (0.0,)):  # parallels: the sphere's shape
            r0 = np.sqrt(1 - z0 * z0)
            ax.plot(r0 * np.cos(t), r0 * np.sin(t), np.full_like(t, z0), color="0.6", linewidth=0.5)
        for lim in (ax.set_xlim, ax.set_ylim, ax.set_zlim):
            lim(-1.0, 1.0)
        ax.set_box_aspect((1, 1, 1), zoom=1.35)
        ax.view_init(elev=np.degrees(elev), azim=np.degrees(azim))
        ax.set_axis_off()
        ax.set_title("on the sphere (z up)", fontsize=7)

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
        ax.scatter([mo[0]], [mo[1]], marker="x", s=60, color=M_O, label="m_o (cloud centroid)", zorder=6)
        ax.set_aspect("equal", adjustable="datalim")
        self._head(ax, support, f"c = {_fmt(sup.value)} = 1 - |m_o - m_s| / M")
        ax.set_xlabel("main axes of the cloud points", fontsize=7)
        self._legend(ax)

    def _smoothness(self, ax: Any, support: ElementSupport) -> None:
        """Each compared direction's score |1 - 2 theta / pi| against its angle theta to the point's
        tangent (a skeletal point) or to the other edge (a curve vertex), on the score's curve; the
        one setting the value marked."""
        sup = support.detail
        theta = np.linspace(0.0, 180.0, 181)
        ax.plot(theta, np.abs(1.0 - 2.0 * np.radians(theta) / np.pi), color="0.75", linewidth=1.0,
                label="|1 - 2θ/π|")
        if sup.tangent is not None:  # a skeletal point: one angle per neighbour
            cos = np.clip(sup.neighbour_tangents @ sup.tangent, -1.0, 1.0)
            angles = np.degrees(np.arccos(cos))
            others = [j for j in range(len(angles)) if j != sup.worst and np.isfinite(angles[j])]
            ax.scatter(angles[others], sup.scores[others], s=22, color=RING, label="neighbours' tangents", zorder=4)
            what = f"s = {_fmt(sup.value)}: min over {len(angles)} neighbours"
            worst_label = f"setting s (θ = {np.degrees(sup.theta):.1f}°)"
        else:  # a curve vertex: the angle between its two edges
            what = f"s = {_fmt(sup.value)}: angle between its two edges"
            worst_label = f"its two edges (θ = {np.degrees(sup.theta):.1f}°)"
        ax.scatter([np.degrees(sup.theta)], [sup.value], s=60, marker="D", color=CENTRE, label=worst_label, zorder=5)
        ax.set_xlim(0, 180)
        ax.set_ylim(-0.03, 1.05)
        ax.set_xticks([0, 45, 90, 135, 180])
        self._head(ax, support, what)
        ax.set_xlabel("θ (degrees)", fontsize=7)
        ax.set_ylabel("score", fontsize=7)
        self._legend(ax)


def _rgba(colour: str) -> np.ndarray:
    from matplotlib.colors import to_rgba

    return np.asarray(to_rgba(colour))


def _fmt(v: float) -> str:
    return format_score(v, 3)
