"""The two H0 barcodes (docs/metrics.md 1): the K compared bars of the cloud and of the skeletal point set,
eps* marked, d_B and d_Wp in the title. Drawn on the panel's own matplotlib Figure (no pyplot, no
global rc), so the viewer never changes anyone else's plots.

The persistence axis keeps its labels inside the panel at any width (a label such as "0.0200" is not cut at
the right edge): the margins are set in pixels on every resize, the labels are the shortest form of
each value ("0.02", not "0.0200") and there are only as many as the width holds. The hint shown
before a result wraps to the panel's width (docs/guide/viewer.md: nothing is cut off sideways)."""

from __future__ import annotations

from typing import Any

import numpy as np
from PySide6 import QtCore, QtWidgets

from ._plot import PlotPanel
from skelcore.scores import format_score


def compared_bars(barcode: np.ndarray, k: int) -> np.ndarray:
    """The K longest bars (the barcode is stored longest first, the infinite bar first)."""
    bars = np.asarray(barcode, dtype=float).reshape(-1, 2)
    order = np.argsort(-(bars[:, 1] - bars[:, 0]), kind="stable")
    return bars[order[: max(int(k), 0)]]


_HINT = "H0 barcodes appear here after an evaluation with a skeletal point set"  # wrapped to the panel
MARGINS_PX = {"left": 46, "right": 16, "top": 30, "bottom": 36}
"""Room around the two axes, in device-independent pixels: y labels, the last x tick label's right half,
title, x labels."""
TITLE_MARGIN_PX = 6  # the title's least distance from either edge (else it goes on two lines)
TITLE_LINE_PX = 14  # the top margin's growth for a title on two lines
TICK_SPACING_PX = 52  # at least this much width per persistence tick label
HINT_LINE_PX = 300  # the hint's longest line in a wide panel (device-independent pixels)


def tick_text(value: float, _pos: object = None) -> str:
    """A persistence tick's label: the value's shortest form (``0.02``, ``0.0025``, ``0``)."""
    text = f"{value:.6g}"
    return "0" if text in ("-0", "0") else text


class BarcodePanel(PlotPanel):
    def __init__(self, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__((4.0, 3.6), 220, _HINT, parent)

    def _axes(self) -> Any:
        """Two axes made once and reused: creating and clearing axes is most of a redraw's cost."""
        if getattr(self, "_bar_axes", None) is None:
            self._bar_axes = self.figure.subplots(
                2, 1, sharex=True, gridspec_kw=dict(left=0.16, right=0.97, top=0.9, bottom=0.13, hspace=0.12)
            )
            from matplotlib.ticker import FuncFormatter, MaxNLocator

            for ax in self._bar_axes:
                ax.tick_params(labelsize=7)
                ax.set_yticks([])
            self._bar_axes[1].set_xlabel("persistence (normalized units)", fontsize=8)
            self._bar_axes[1].xaxis.set_major_formatter(FuncFormatter(tick_text))
            self._locator = MaxNLocator(nbins=5, steps=[1, 2, 2.5, 5, 10], min_n_ticks=2)
            self._bar_axes[1].xaxis.set_major_locator(self._locator)
            self._empty = self.figure.text(0.5, 0.5, _HINT, ha="center", va="center", color="0.4")
            self._title = self.figure.suptitle("", fontsize=9)
            self.canvas.mpl_connect("resize_event", lambda _event: self.fit_margins())
            self.fit_margins()
        return self._bar_axes

    def fit_margins(self) -> None:
        """Margins of a fixed size in pixels (a fraction of a narrow panel is too little for the
        labels, of a wide one too much), and as many x ticks as the width holds."""
        fig = self.figure
        ratio = float(getattr(self.canvas, "device_pixel_ratio", 1.0) or 1.0)  # Qt's scale factor: text grows too
        w, h = fig.bbox.width / ratio, fig.bbox.height / ratio  # device-independent pixels
        m = dict(MARGINS_PX)
        if w <= 0:
            return
        self._wrap_hint(w, ratio)
        if w < 4 * (m["left"] + m["right"]) / 3 or h < 2 * (m["top"] + m["bottom"]):
            return  # not laid out yet (or absurdly small): keep the previous margins
        if self._wrap_title(w, ratio):
            m["top"] += TITLE_LINE_PX
        self._bar_axes[0].get_gridspec().update(left=m["left"] / w, right=1 - m["right"] / w,
                                                top=1 - m["top"] / h, bottom=m["bottom"] / h)
        for ax in self._bar_axes:  # GridSpec.update moves the axes of pyplot's figures only
            ax.set_position(ax.get_subplotspec().get_position(fig))
        self._locator.set_params(nbins=max(2, int((w - m["left"] - m["right"]) / TICK_SPACING_PX)))

    def prepare(self) -> None:
        """Create the figure and axes ahead of the first result (they cost ~50-80 ms), then, in a
        later event-loop turn, warm matplotlib's caches for the first result's draw."""
        if not self.has_figure:
            self._axes()
            self.show_topology(None)
            timer = QtCore.QTimer(self)  # a child: it dies with the panel
            timer.setSingleShot(True)
            timer.timeout.connect(self._warm_up)
            timer.start(100)
            self._warm_up_timer = timer

    def _warm_up(self) -> None:
        """Lay the axes out once with their ticks showing (~20 ms, nothing rasterized): that fills
        matplotlib's font and text-layout caches, without which the first result's draw takes about
        twice as long (measured 80 -> 35 ms)."""
        axes = self._axes()
        shown = [ax.get_visible() for ax in axes]
        for ax in axes:
            ax.set_visible(True)
        self.figure.draw_without_rendering()
        for ax, visible in zip(axes, shown):
            ax.set_visible(visible)

    def show_topology(self, topology: Any) -> None:
        """Draw the compared bars of both diagrams, or a hint when there is no topology result."""
        if topology is None and not self.has_figure:
            return  # the start-up hint label is showing
        from matplotlib.collections import LineCollection

        axes = self._axes()
        for ax in axes:
            for artist in [*ax.collections, *ax.lines]:
                artist.remove()
            legend = ax.get_legend()
            if legend is not None:
                legend.remove()
            ax.set_visible(topology is not None)
        self._empty.set_visible(topology is None)
        if topology is None:
            self._title.set_text("")
            self._title_lines = None
            self.fit_margins()
            self.request_draw()
            return
        k = int(topology.n_bars)
        cloud = compared_bars(topology.cloud_barcode, k)
        skel = compared_bars(topology.skeletal_barcode, k)
        finite = np.concatenate([cloud[np.isfinite(cloud[:, 1]), 1], skel[np.isfinite(skel[:, 1]), 1], [topology.eps_star]])
        x_end = float(finite.max()) * 1.08 if finite.size and finite.max() > 0 else 1.0
        for ax, bars, name, colour in ((axes[0], cloud, "cloud", "#1f4e79"), (axes[1], skel, "skeletal points", "#b35900")):
            deaths = np.where(np.isfinite(bars[:, 1]), bars[:, 1], x_end)
            y = np.arange(len(bars))
            # A LineCollection from one (n, 2, 2) array: ax.hlines goes through masked arrays per
            # bar and costs ~10 ms for a few hundred bars.
            segments = np.stack([np.column_stack([bars[:, 0], y]), np.column_stack([deaths, y])], axis=1)
            ax.add_collection(LineCollection(segments, colors=colour, linewidths=1.0 if len(bars) < 80 else 0.6))
            inf_rows = ~np.isfinite(bars[:, 1])
            if inf_rows.any():  # the infinite bar runs off the plot
                ax.plot(np.full(inf_rows.sum(), x_end), y[inf_rows], marker=">", color=colour, linestyle="none",
                        markersize=5)
            ax.axvline(topology.eps_star, color="crimson", linestyle="--", linewidth=1.0, label="eps*")
            ax.set_ylim(len(bars) - 0.5 if len(bars) else 1, -0.5 - max(len(bars) * 0.02, 0.5))
            ax.set_ylabel(f"{name}\n({len(bars)} bars)", fontsize=8)
        axes[0].legend(loc="lower right", fontsize=7, frameon=False)
        axes[1].set_xlim(0, x_end * 1.03)
        self._title_lines = (f"H0, K = {k}:", f"d_B = {_fmt(topology.bottleneck)},  d_Wp = {_fmt(topology.wasserstein)}")
        self._title.set_text("  ".join(self._title_lines))
        self.fit_margins()  # on two lines if the panel is too narrow for one
        self.request_draw()

    def _wrap_title(self, width: float, ratio: float) -> bool:
        """The title on one line if it fits ``width`` (device-independent pixels) with a margin on each
        side, else on two (K, then the distances); whether it is on two."""
        lines = getattr(self, "_title_lines", None)
        if not lines or not self._title.get_text():
            return False
        self._title.set_text("  ".join(lines))
        one = self._title.get_window_extent(renderer=self.canvas.get_renderer()).width / ratio
        if one <= width - 2 * TITLE_MARGIN_PX:
            return False
        self._title.set_text("\n".join(lines))
        return True

    def _wrap_hint(self, width: float, ratio: float) -> None:
        """The hint broken into lines between words where a line would come nearer than TITLE_MARGIN_PX
        to either edge of ``width`` (device-independent pixels), or pass HINT_LINE_PX: never cut sideways."""
        room = min(width - 2 * TITLE_MARGIN_PX, HINT_LINE_PX)
        renderer = self.canvas.get_renderer()

        def fits(line: str) -> bool:
            self._empty.set_text(line)
            return self._empty.get_window_extent(renderer=renderer).width / ratio <= room

        lines, line = [], ""
        for word in _HINT.split():
            if line and not fits(f"{line} {word}"):
                lines.append(line)
                line = word
            else:
                line = f"{line} {word}" if line else word
        self._empty.set_text("\n".join([*lines, line]))

    def _draw_stages(self) -> list[list[Any]] | None:
        """The cloud's diagram, then the skeletal points' (~20-30 ms each in Agg): two event-loop
        turns instead of one twice as long. Same pixels as a whole-figure draw (Figure.draw's order:
        background, axes, then the figure texts)."""
        if getattr(self, "_bar_axes", None) is None:
            return None
        fig = self.figure
        return [[fig.patch, self._bar_axes[0]], [self._bar_axes[1], self._title, self._empty]]

    def title(self) -> str:
        return self._title.get_text() if self.has_figure else ""


def _fmt(v: float) -> str:
    return format_score(v, 4)
