"""``Evaluation.show``, ``Evaluation.show_barcodes`` and ``skelcore.show_ab``: a picture of an
evaluation wherever the user is. In a Jupyter notebook it is drawn in the cell (the
3-D scene through pyvista's notebook support: a static picture by default, trame's interactive view
with ``jupyter_backend="trame"`` when trame is installed); given ``path=``, or with no display, it is
written as a PNG and its path returned; else it opens in a window. The scenes are
:mod:`.scene`'s (viridis, magenta = invalid, docs/metrics.md 5.5), the tables :mod:`.summary_table`'.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import Any, Callable, Sequence

from ..errors import SkelInputError
from ..io.atomic import atomic_open
from ..scores import LOCAL_METRICS
from .picture_arrays import drawing_arrays
from .scene import SKELETON_VIEW
from .where import has_display, in_notebook

__all__ = ["VIEWS", "show", "show_barcodes", "show_ab"]

#: what ``show`` draws: the plain skeleton or one local metric
VIEWS = (SKELETON_VIEW, *LOCAL_METRICS)
_SIZE = (640, 480)


def _check_view(metric: str) -> None:
    if metric not in VIEWS:
        raise ValueError(f"unknown metric {metric!r} (known: {', '.join(VIEWS)})")


def _free_name(stem: str) -> Path:
    """``stem.png`` in the current folder, or ``stem_2.png``, ... : never a file that exists."""
    path, n = Path(f"{stem}.png"), 1
    while path.exists():
        n += 1
        path = Path(f"{stem}_{n}.png")
    return path


def _write(path: str | os.PathLike, data: bytes, inputs: Sequence[str]) -> Path:
    path = Path(path)
    if path.suffix.lower() != ".png":
        raise SkelInputError("a picture is written as PNG: give a path ending in .png", path)
    with atomic_open(path, "wb", inputs=inputs) as fh:
        fh.write(data)
    return path


def _deliver(path: str | os.PathLike | None, stem: str, inputs: Sequence[str], png: Callable[[], bytes],
             notebook: Callable[[], None], window: Callable[[], None]) -> Path | None:
    """The one decision: ``path`` given -> that PNG; a notebook -> the cell; a display -> a window;
    else a new PNG in the current folder. Returns the PNG's path, or None when nothing was written."""
    if path is None and in_notebook():
        notebook()
        return None
    if path is None and has_display():
        window()
        return None
    written = _write(path if path is not None else _free_name(stem), png(), inputs)
    if path is None:
        print(f"skelscope: no display: wrote {written}", file=sys.stderr)
    return written


def _display(*objects: Any) -> None:
    from IPython.display import display

    display(*objects)


def _in_cell(panels: Sequence[Any], metric: str, size: tuple[int, int], backend: str, options: dict) -> None:
    """The scene in the notebook's cell through pyvista (a static picture is closed once shown; an
    interactive backend keeps its plotter)."""
    from .plotter import make_plotter

    pl = make_plotter(panels, metric, size, notebook=True, **options)
    pl.show(jupyter_backend=backend)
    if backend == "static":
        pl.close()


def show(ev: Any, metric: str = "centeredness", *, path: str | os.PathLike | None = None,
         jupyter_backend: str = "static", size: tuple[int, int] = _SIZE, clim: tuple[float, float] = (0.0, 1.0),
         colour_bar: bool = True, prefer: str = "curve", point_size: float = 7.0) -> Path | None:
    """The skeleton coloured by ``metric`` (or "skeleton": plain) over the faint cloud, with the colour
    bar (NaN magenta). The curve skeleton is coloured when there is one (``prefer="skeletal"``: the
    skeletal set first). Returns the PNG's path when one was written (``path=``, or no display)."""
    _check_view(metric)
    arrays = drawing_arrays(ev)
    options = dict(colour_bar=colour_bar, clim=clim, prefer=prefer, point_size=point_size)
    panels = [(arrays, None)]

    def png() -> bytes:
        from .plotter import render_png

        return render_png(panels, metric, size, **options)

    def notebook() -> None:
        _in_cell(panels, metric, size, jupyter_backend, options)

    def window() -> None:
        from .plotter import make_plotter

        make_plotter(panels, metric, size, **options).show(title=f"SkelScope: {metric}")

    return _deliver(path, f"skelscope_{metric}", ev._input_paths(), png, notebook, window)


def show_barcodes(ev: Any, *, path: str | os.PathLike | None = None, size: tuple[int, int] = (560, 420),
                  dpi: int = 100) -> Path | None:
    """The H0 barcodes of the cloud and the skeletal set (docs/metrics.md 1), drawn as compare's figure draws
    them, titled like the viewer's panel. Returns the PNG's path when one was written."""
    from .barcodes import barcode_title

    arrays = drawing_arrays(ev)
    title = None if ev.topology is None else barcode_title(ev.topology)

    def png() -> bytes:
        from .barcodes import barcode_figure, figure_png

        return figure_png(barcode_figure(arrays, size, dpi=dpi, title=title))

    def notebook() -> None:
        from IPython.display import Image

        _display(Image(data=png(), format="png"))

    def window() -> None:
        import matplotlib.pyplot as plt

        from .barcodes import fill_barcode_figure

        fill_barcode_figure(plt.figure(figsize=(size[0] / dpi, size[1] / dpi), dpi=dpi), arrays, title)
        plt.show()

    return _deliver(path, "skelscope_barcodes", ev._input_paths(), png, notebook, window)


def show_ab(ev_a: Any, ev_b: Any, metric: str = "centeredness", *, labels: tuple[str, str] = ("A", "B"),
            path: str | os.PathLike | None = None, jupyter_backend: str = "static", size: tuple[int, int] = _SIZE,
            clim: tuple[float, float] = (0.0, 1.0), prefer: str = "curve", point_size: float = 7.0) -> Path | None:
    """Two evaluations side by side, coloured by ``metric`` over the same colour range ``clim`` (one
    colour bar) with linked cameras, and their two summary tables (HTML in a notebook, else text on
    stdout). Returns the PNG's path when one was written."""
    _check_view(metric)
    panels = [(drawing_arrays(ev_a), labels[0]), (drawing_arrays(ev_b), labels[1])]
    options = dict(colour_bar=True, clim=clim, prefer=prefer, point_size=point_size)
    inputs = (*ev_a._input_paths(), *ev_b._input_paths())

    def png() -> bytes:
        from .plotter import render_png

        return render_png(panels, metric, size, **options)

    def notebook() -> None:
        from IPython.display import HTML

        from .summary_table import tables_html

        _in_cell(panels, metric, size, jupyter_backend, options)
        _display(HTML(tables_html((ev_a, ev_b), labels)))

    def window() -> None:
        from .plotter import make_plotter

        make_plotter(panels, metric, size, **options).show(title=f"SkelScope: {labels[0]} | {labels[1]}: {metric}")

    if path is not None or not in_notebook():
        _print_tables((ev_a, ev_b), labels)
    return _deliver(path, f"skelscope_ab_{metric}", inputs, png, notebook, window)


def _print_tables(evaluations: Sequence[Any], labels: Sequence[str]) -> None:
    from .summary_table import format_defects, format_table

    for ev, label in zip(evaluations, labels):
        print(f"{label}:\n{format_table(ev.scores())}\n{format_defects(ev.warning_dicts(), ev.not_computed)}\n")
