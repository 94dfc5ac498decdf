"""Everything the viewer writes: coloured PLY, PNG screenshots, JSON and per-element CSV.

PLY, JSON and CSV go through skelcore's own writers (the same files ``skelcore evaluate`` writes);
every file is written atomically and never over a loaded input (``skelcore.io.atomic``).
"""

from __future__ import annotations

import dataclasses
import os
from typing import Any, Iterable

import numpy as np

from skelcore.io.atomic import atomic_open

__all__ = ["with_thresholds", "export_coloured_ply", "export_results", "write_png"]


def with_thresholds(evaluation: Any, beta_star: float, c_star: float) -> Any:
    """The evaluation as shown: same local values, the viewer's beta* and c* (SPEC 2-3)."""
    params = evaluation.params.replace(beta_star=float(beta_star), c_star=float(c_star))
    return dataclasses.replace(evaluation, params=params)


def export_coloured_ply(evaluation: Any, out_dir: str | os.PathLike, inputs: Iterable[str] = (),
                        color_by: str = "centeredness") -> list[str]:
    """Skeletal points, curve vertices with edges and curve samples as coloured PLY, RGB by the metric
    on screen and one float property per local metric (``skelcore.io.export.export_ply``)."""
    from skelcore.io.export import export_ply

    return [str(p) for p in export_ply(evaluation, str(out_dir), inputs=tuple(inputs), color_by=color_by)]


def export_results(evaluation: Any, prefix: str | os.PathLike, inputs: Iterable[str] = ()) -> list[str]:
    """``PREFIX.json``, ``PREFIX_skeletal.csv`` / ``_curve_samples.csv`` / ``_curve_vertices.csv`` and
    ``PREFIX_barcodes.csv``, exactly as ``skelcore evaluate --json --per-point --barcodes`` writes them."""
    prefix = str(prefix)
    if prefix.endswith(".json"):
        prefix = prefix[: -len(".json")]
    guard = tuple(inputs)
    written = [f"{prefix}.json"]
    evaluation.write_json(written[0], inputs=guard)
    written += evaluation.write_per_point(prefix, inputs=guard)
    if evaluation.topology is not None:
        path = f"{prefix}_barcodes.csv"
        evaluation.write_barcodes(path, inputs=guard)
        written.append(path)
    return written


def write_png(path: str | os.PathLike, image: np.ndarray, inputs: Iterable[str] = ()) -> str:
    """Write an (H, W, 3|4) uint8 image as PNG, atomically (alpha kept for transparent screenshots)."""
    from matplotlib.image import imsave

    img = np.asarray(image)
    if img.ndim != 3 or img.shape[2] not in (3, 4) or img.dtype != np.uint8:
        raise ValueError(f"expected an (H, W, 3|4) uint8 image, got {img.shape} {img.dtype}")
    with atomic_open(path, "wb", inputs=inputs) as fh:
        imsave(fh, img, format="png")
    return str(path)
