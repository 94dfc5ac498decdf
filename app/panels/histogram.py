"""Histogram of the selected local metric (skeletal points and curve elements) with the threshold
line an overall score counts against (beta* for boundedness, c* for centeredness; docs/metrics.md 2-3). Results
out of date (a setting changed) are drawn grey, with the reason."""

from __future__ import annotations

from typing import Any

import numpy as np
from PySide6 import QtWidgets

from ..scene import Scene
from ._plot import PlotPanel

_LABELS = {"skeletal": "skeletal points", "curve": "curve"}
_COLOURS = {"skeletal": "#b35900", "curve": "#1f4e79"}
_STALE_COLOURS = {"skeletal": "#9a9a9a", "curve": "#c8c8c8"}


class HistogramPanel(PlotPanel):
    def __init__(self, parent: QtWidgets.QWidget | None = None) -> None:
        super().__init__((4.0, 2.6), 180, "a histogram of the selected local metric\nappears here after an evaluation", parent)
        self.threshold: float | None = None
        self.stale = ""  # the reason the drawn values are out of date, "" when they are not

    def show_scene(self, scene: Scene) -> None:
        has_values = any(
            layer.quantity(scene.metric) is not None for name, layer in scene.layers.items() if name != "cloud"
        )
        if not has_values and not self.has_figure:
            self.threshold = None
            return  # the start-up hint label is showing
        ax = self._axes()
        metric = scene.metric
        series: list[tuple[str, np.ndarray, int]] = []
        for name in ("skeletal", "curve"):
            layer = scene.layers.get(name)
            q = None if layer is None else layer.quantity(metric)
            if q is not None:
                finite = q.values[np.isfinite(q.values)]
                series.append((name, finite, q.n_invalid))
        ax.set_axis_on()
        if not series:
            ax.set_axis_off()
            ax.text(0.5, 0.5, f"no {metric} values yet", ha="center", va="center", transform=ax.transAxes,
                    color="0.4")
            self.threshold = None
            self.request_draw()
            return
        lo, hi = 0.0, 1.0
        for _, finite, _ in series:
            if finite.size:
                lo, hi = min(lo, float(finite.min())), max(hi, float(finite.max()))
        bins = np.linspace(lo, hi, 26)
        self.stale = scene.stale
        colours = _STALE_COLOURS if self.stale else _COLOURS
        for name, finite, n_nan in series:
            label = f"{_LABELS[name]} (n = {finite.size}" + (f", {n_nan} nan)" if n_nan else ")")
            # Each series as fractions of its own size, so 4096 points and 200 samples compare.
            fractions = np.histogram(finite, bins=bins)[0] / max(finite.size, 1)
            # One filled step patch per series (ax.hist makes a Rectangle per bin: ~10x slower to build).
            ax.stairs(fractions, bins, fill=True, alpha=0.55, color=colours[name], label=label)
        self.threshold = scene.threshold_for(metric)
        if self.threshold is not None:
            star = "beta*" if metric == "boundedness" else "c*"
            ax.axvline(self.threshold, color="0.6" if self.stale else "crimson", linestyle="--", linewidth=1.2,
                       label=f"{star} = {self.threshold:.2f}")
        if self.stale:
            ax.text(0.98, 0.97, f"{self.stale}: re-run (F5)", ha="right", va="top", transform=ax.transAxes,
                    fontsize=7, color="#8a4b00")
        ax.set_xlabel(metric, fontsize=8)
        ax.set_ylabel("fraction", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.legend(fontsize=7, frameon=False, loc="upper left")
        self.request_draw()

    def _axes(self) -> Any:
        """The axes, made once and emptied for each redraw: clearing the figure and making new
        axes is most of a redraw's cost."""
        fig = self.figure
        if not fig.axes:
            fig.add_subplot(1, 1, 1)
            fig.subplots_adjust(left=0.14, right=0.97, top=0.95, bottom=0.17)  # no layout engine (hidden tabs)
        ax = fig.axes[0]
        for artist in [*ax.patches, *ax.lines, *ax.texts]:
            artist.remove()
        legend = ax.get_legend()
        if legend is not None:
            legend.remove()
        ax.relim()
        ax.autoscale()
        return ax

    def axes(self) -> Any:
        return self.figure.axes[0] if self.has_figure and self.figure.axes else None
