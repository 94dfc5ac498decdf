"""A pyvista plotter holding one scene per panel, side by side, for a window, a notebook or a PNG
rendered off-screen. compare's renders, ``Evaluation.show`` and ``show_ab`` all make their plotter
and their PNG here (one rendering code path, the colours of docs/metrics.md 5.5 from :mod:`.scene`).
"""

from __future__ import annotations

import io as _io
from typing import Any, Callable, Sequence

import numpy as np

from .scene import add_scene, quiet_vtk

__all__ = ["Panel", "make_plotter", "render_png", "png_bytes", "OffscreenPlotter"]

#: one panel: the drawing arrays (:func:`skelcore.display.picture_arrays.drawing_arrays`) and its title (or None)
Panel = tuple[dict[str, np.ndarray], "str | None"]


def make_plotter(panels: Sequence[Panel], view: str, size: tuple[int, int], *, off_screen: bool = False,
                 notebook: bool = False, colour_bar: bool = False, **scene: Any) -> Any:
    """A plotter of ``len(panels)`` panels of ``size`` pixels each, every one drawing ``view``
    (:func:`.scene.add_scene`'s options in ``scene``, the same ``clim`` for all); the colour bar, one
    for all, in the last panel. The cameras are linked when there are several."""
    import pyvista as pv

    quiet_vtk()
    n = len(panels)
    kwargs: dict[str, Any] = {"window_size": [int(size[0]) * n, int(size[1])], "shape": (1, n), "border": False}
    if notebook:
        kwargs["notebook"] = True
    elif off_screen:
        kwargs["off_screen"] = True
    pl = pv.Plotter(**kwargs)
    for i, (arrays, title) in enumerate(panels):
        pl.subplot(0, i)
        add_scene(pl, arrays, view, colour_bar=colour_bar and i == n - 1, title=title, **scene)
    if n > 1:
        pl.link_views()
    return pl


def render_png(panels: Sequence[Panel], view: str, size: tuple[int, int], **options: Any) -> bytes:
    """The panels rendered off-screen, as PNG bytes (:func:`make_plotter`'s options)."""
    pl = make_plotter(panels, view, size, off_screen=True, **options)
    try:
        img = pl.screenshot(return_img=True)
    finally:
        pl.close()
    return png_bytes(img)


class OffscreenPlotter:
    """One off-screen single-panel plotter of ``size`` pixels reused for many pictures (compare's
    report draws five per job): a new VTK render window per picture pays its OpenGL context and
    shaders again (under llvmpipe about 0.1 s of a 320-pixel picture's 0.25 s, docs/performance.md
    6.11). Cleared before each picture, it gives the same PNG bytes as a plotter of
    its own, rendered once per picture (6.12). A context manager; ``png(draw)`` calls ``draw(plotter)``
    and returns the PNG."""

    def __init__(self, size: tuple[int, int]) -> None:
        self.size = (int(size[0]), int(size[1]))
        self._pl: Any = None  # made at the first picture: a run whose pictures are all cached needs none

    def png(self, draw: Callable[[Any], None]) -> bytes:
        if self._pl is None:
            import pyvista as pv

            quiet_vtk()
            self._pl = pv.Plotter(off_screen=True, window_size=list(self.size), border=False)
        pl = self._pl
        pl.suppress_rendering = True  # once drawn, pyvista renders at every actor added and camera reset
        try:
            pl.clear()
            draw(pl)
        finally:
            pl.suppress_rendering = False
        pl.render()  # the one render of the picture (a no-op before the first screenshot, which renders)
        return png_bytes(pl.screenshot(return_img=True))

    def close(self) -> None:
        if self._pl is not None:
            self._pl.close()
            self._pl = None

    def __enter__(self) -> "OffscreenPlotter":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def png_bytes(img: np.ndarray) -> bytes:
    """An (H, W, 3|4) uint8 image as PNG bytes (matplotlib's writer, imported here; no backend is
    chosen, so a notebook's inline plots are left alone)."""
    from matplotlib import image as mpimg

    buf = _io.BytesIO()
    mpimg.imsave(buf, np.ascontiguousarray(img), format="png")
    return buf.getvalue()
