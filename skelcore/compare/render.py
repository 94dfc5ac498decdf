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
from ..display.plotter import render_png
from ..io.atomic import atomic_open
from ..scores import LOCAL_METRICS

__all__ = ["VIEWS", "render_job", "draw_barcodes", "barcode_png"]

VIEWS = ("skeleton", "barcodes", *LOCAL_METRICS)
_SIZE = (320, 320)


def render_job(out_dir: str | os.PathLike, key: str, arrays: dict[str, np.ndarray],
               size: tuple[int, int] = _SIZE) -> dict[str, Path]:
    """PNG path per view of the job, rendered once (cached in ``out_dir/renders``)."""
    folder = Path(out_dir) / "renders"
    folder.mkdir(exist_ok=True)
    paths = {}
    for view in VIEWS:
        path = folder / f"{key}_{view}.png"
        if not path.exists():
            data = barcode_png(arrays, size) if view == "barcodes" else render_png([(arrays, None)], view, size)
            with atomic_open(path, "wb") as fh:
                fh.write(data)
        paths[view] = path
    return paths
