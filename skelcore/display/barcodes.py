"""The two H0 barcodes of a picture (docs/metrics.md 1, the paper's barcode figure): the cloud's K compared bars
(grey) above the skeletal set's (blue), eps* dashed. compare's report and ``skelcore figure`` draw
them with :func:`draw_barcodes`; ``Evaluation.show_barcodes`` with :func:`barcode_figure`.

matplotlib is imported inside the functions, and only its ``Figure`` (no pyplot, no backend chosen).
"""

from __future__ import annotations

import io as _io
from typing import Any

import numpy as np

from .. import colors
from .tight_once import tight_layout_once

__all__ = ["draw_barcodes", "fill_barcode_figure", "barcode_figure", "barcode_title", "barcode_png", "figure_png"]


def _unit(rgb: tuple[int, int, int]) -> tuple[float, float, float]:
    return tuple(c / 255 for c in rgb)  # type: ignore[return-value]


def draw_barcodes(ax: Any, arrays: dict[str, np.ndarray]) -> None:
    """Both H0 barcodes on one axis: the cloud's (grey) above the skeleton's (blue), the K compared
    bars drawn solid, eps* dashed (paper, Fig. "barcodes"; docs/metrics.md 1)."""
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
        ax.hlines(y, bars[:, 0], deaths, color=_unit(colour), linewidth=max(0.3, min(2.0, 80 / max(k, 1))))
        rows = max(rows, offset * (k + 2) + len(bars))
    ax.axvline(eps, color="k", linestyle="--", linewidth=0.8)
    ax.set_ylim(rows + 1, -1)
    ax.set_xlim(0, cap)
    ax.set_yticks([k / 2, (k + 2) + k / 2], ["cloud", "skeleton"], fontsize=7)
    ax.tick_params(axis="x", labelsize=6)
    ax.set_xlabel("filtration radius (normalized)", fontsize=7)


def fill_barcode_figure(fig: Any, arrays: dict[str, np.ndarray], title: str | None = None) -> Any:
    """Draw :func:`draw_barcodes`' axis into an empty figure (a ``Figure`` or pyplot's, for a window)."""
    ax = fig.add_subplot(1, 1, 1)
    draw_barcodes(ax, arrays)
    if title:
        ax.set_title(title, fontsize=8)
    return tight_layout_once(fig)


def barcode_title(topology: Any) -> str:
    """The viewer's barcode title: K and both distances (docs/metrics.md 1)."""
    from ..scores import format_score

    return (f"H0, K = {int(topology.n_bars)}:  d_B = {format_score(topology.bottleneck, 4)},  "
            f"d_Wp = {format_score(topology.wasserstein, 4)}")


def barcode_figure(arrays: dict[str, np.ndarray], size: tuple[int, int] = (320, 320), *, dpi: int = 100,
                   title: str | None = None) -> Any:
    """A matplotlib ``Figure`` of ``size`` pixels at ``dpi`` with :func:`draw_barcodes`' axis."""
    from matplotlib.figure import Figure

    return fill_barcode_figure(Figure(figsize=(size[0] / dpi, size[1] / dpi), dpi=dpi), arrays, title)


def figure_png(fig: Any) -> bytes:
    """A matplotlib Figure as PNG bytes."""
    buf = _io.BytesIO()
    fig.savefig(buf, format="png")
    return buf.getvalue()


def barcode_png(arrays: dict[str, np.ndarray], size: tuple[int, int] = (320, 320)) -> bytes:
    """:func:`barcode_figure` as PNG bytes (compare's ``renders/KEY_barcodes.png``)."""
    return figure_png(barcode_figure(arrays, size))
