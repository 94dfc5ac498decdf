"""Everything the viewer writes: coloured PLY, PNG screenshots, JSON and per-element CSV.

PLY, JSON and CSV go through skelcore's own writers (the same files ``skelcore evaluate`` writes);
every file is written atomically and never over a loaded input (``skelcore.io.atomic``). Files are
named after the data (``<cloud stem>_skeletal.ply``, ...); the ``*_names`` functions list what an
export would write, so the window asks before replacing an existing file.
"""

from __future__ import annotations

import dataclasses
import os
from typing import Any, Iterable

import numpy as np

from skelcore.io.atomic import atomic_open

__all__ = ["with_thresholds", "data_stem", "ply_export_names", "export_coloured_ply", "result_export_names",
           "export_results", "write_png"]

_PLY_PARTS = ("skeletal", "curve", "curve_samples")


def data_stem(paths: dict[str, str | None]) -> str:
    """What exports are named after: the cloud's file stem, else the skeletal set's or the curve's,
    else "skelscope" (in-memory data such as a study variant)."""
    for role in ("cloud", "skeletal", "curve"):
        path = paths.get(role)
        if path:
            return os.path.splitext(os.path.basename(str(path)))[0]
    return "skelscope"


def ply_export_names(evaluation: Any, out_dir: str | os.PathLike, stem: str) -> list[str]:
    """The files :func:`export_coloured_ply` writes for ``evaluation`` into ``out_dir``."""
    parts = (["skeletal"] if evaluation.skeletal is not None else []) + \
        (["curve", "curve_samples"] if evaluation.curve is not None else [])
    return [os.path.join(str(out_dir), f"{stem}_{part}.ply") for part in parts]


def with_thresholds(evaluation: Any, beta_star: float, c_star: float) -> Any:
    """The evaluation as shown: same local values, the viewer's beta* and c* (docs/metrics.md 2-3)."""
    params = evaluation.params.replace(beta_star=float(beta_star), c_star=float(c_star))
    return dataclasses.replace(evaluation, params=params)


def export_coloured_ply(evaluation: Any, out_dir: str | os.PathLike, inputs: Iterable[str] = (),
                        color_by: str = "centeredness", stem: str = "skelscope",
                        mappings: dict[str, Any] | None = None) -> list[str]:
    """Skeletal points, curve vertices with edges and curve samples as coloured PLY, RGB by the metric
    on screen and one float property per local metric (``skelcore.io.export.export_ply``), named
    ``<stem>_skeletal.ply``, ``<stem>_curve.ply``, ``<stem>_curve_samples.ply``. ``mappings``: each
    skeleton layer's ``(scale, offset)`` into the cloud's frame (``Layer.mapping``), said in the header.

    skelcore writes fixed names into a folder: they are written into a private folder beside the
    targets, then each renamed into place (atomic); a loaded input is never a target."""
    import shutil
    import tempfile

    from skelcore.errors import SkelInputError
    from skelcore.io.export import export_ply

    guard = {os.path.realpath(p) for p in inputs if p}
    targets = ply_export_names(evaluation, out_dir, stem)
    for target in targets:
        if os.path.realpath(target) in guard:
            raise SkelInputError("refusing to overwrite an input file", target)
    os.makedirs(str(out_dir), exist_ok=True)
    staging = tempfile.mkdtemp(prefix=".skelscope-export-", dir=str(out_dir))
    try:
        written = export_ply(evaluation, staging, inputs=tuple(inputs), color_by=color_by, mappings=mappings)
        by_part = {os.path.splitext(os.path.basename(str(p)))[0]: str(p) for p in written}
        out = []
        for target in targets:
            part = os.path.basename(target)[len(stem) + 1: -len(".ply")]
            os.replace(by_part[part], target)
            out.append(target)
        return out
    finally:
        shutil.rmtree(staging, ignore_errors=True)


def result_export_names(evaluation: Any, prefix: str | os.PathLike) -> list[str]:
    """The files :func:`export_results` writes for ``evaluation`` under ``prefix``."""
    prefix = str(prefix)
    if prefix.endswith(".json"):
        prefix = prefix[: -len(".json")]
    names = [f"{prefix}.json"]
    if evaluation.skeletal is not None:
        names.append(f"{prefix}_skeletal.csv")
    if evaluation.curve is not None:
        names += [f"{prefix}_curve_samples.csv", f"{prefix}_curve_vertices.csv"]
    if evaluation.topology is not None:
        names.append(f"{prefix}_barcodes.csv")
    return names


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
