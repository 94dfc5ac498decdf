"""The pictures of one job, as in the paper's graphic table: the skeleton over the cloud, the two H0
barcodes, and the skeleton coloured by boundedness, centeredness and smoothness (viridis, magenta =
invalid, docs/metrics.md 5.5). The scenes and barcodes are drawn by :mod:`skelcore.display` (the code
``Evaluation.show`` uses too); PNGs are cached per job key in ``DIR/renders`` so a rerun redraws nothing.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..display.barcodes import barcode_png, draw_barcodes
from ..display.plotter import OffscreenPlotter, render_png
from ..display.scene import add_scene
from ..io.atomic import atomic_open
from ..scores import LOCAL_METRICS

__all__ = ["VIEWS", "SIZE", "render_job", "draw_barcodes", "barcode_png"]

VIEWS = ("skeleton", "barcodes", *LOCAL_METRICS)
SIZE = (320, 320)  # pixels of each picture of the graphic table


def render_job(out_dir: str | os.PathLike, key: str, arrays: dict[str, np.ndarray],
               size: tuple[int, int] = SIZE, plotter: OffscreenPlotter | None = None) -> dict[str, Path]:
    """PNG path per view of the job, rendered once (cached in ``out_dir/renders``); the 3D views on
    ``plotter`` when one of ``size`` is given (the report's, shared by its jobs: the same bytes, less
    time), else each on a plotter of its own."""
    folder = Path(out_dir) / "renders"
    folder.mkdir(exist_ok=True)
    shared = plotter if plotter is not None and plotter.size == tuple(size) else None
    paths = {}
    for view in VIEWS:
        path = folder / f"{key}_{view}.png"
        if not path.exists():
            if view == "barcodes":
                data = barcode_png(arrays, size)
            elif shared is not None:
                data = shared.png(lambda pl, v=view: add_scene(pl, arrays, v))
            else:
                data = render_png([(arrays, None)], view, size)
            with atomic_open(path, "wb") as fh:
                fh.write(data)
        paths[view] = path
    return paths
