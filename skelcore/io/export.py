"""Coloured PLY export of an Evaluation (CLI ``--export-ply DIR`` and the viewer's File > Export).

Three files, coordinates in the user's units, every local value as a float property with NaN kept
(docs/metrics.md 5.5) and RGB from :mod:`skelcore.colors` (NaN magenta), so MeshLab, CloudCompare or Open3D show
the same picture as the viewer:

- ``skeletal.ply``: skeletal points; boundedness, centeredness (after the unbounded -> 0 rule of
  docs/metrics.md 3, at the evaluation's beta*), smoothness; coloured by ``color_by``.
- ``curve.ply``: curve vertices with the ``edge`` element; smoothness (NaN unless degree 2, docs/metrics.md 4)
  and degree; coloured by smoothness.
- ``curve_samples.ply``: the curve samples (sampled as in docs/metrics.md 3.2); boundedness, centeredness, their edge
  and fraction t; coloured by ``color_by`` (centeredness when ``color_by`` is smoothness, which
  samples do not have).

Each file's header says which metric its colours encode, in one comment line:
``comment colors: centeredness (viridis over [0, 1], NaN magenta)`` (:func:`colour_comment`); and, for
a skeleton mapped into the cloud's frame (``--skeleton-scale`` / ``--skeleton-offset``, the viewer's
Map skeleton), which map gave its coordinates (:func:`mapping_comment`).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Iterable

import numpy as np

from ..colors import METRIC_COLORMAP as COLOUR_MAP, map_to_rgb
from ..errors import SkelInputError
from .ply import write_curve_ply, write_points_ply
from ..evaluation import Evaluation

__all__ = ["export_ply", "COLOR_BY", "colour_comment", "mapping_comment"]

#: Metrics a file can be coloured by. Every metric lives in [0, 1], so the colour range is fixed.
COLOR_BY = ("centeredness", "boundedness", "smoothness")


def colour_comment(metric: str) -> str:
    """The PLY header comment naming the metric the RGB colours encode (and how)."""
    return f"colors: {metric} ({COLOUR_MAP} over [0, 1], NaN magenta)"


def mapping_comment(scale: float, offset: Iterable[float]) -> str:
    """The PLY header comment saying the coordinates were mapped into the cloud's frame, and how (the
    skeleton's own file holds them unmapped)."""
    s = f"{float(scale):.9g}"
    o = " ".join(f"{float(v):.9g}" for v in offset)
    return (f"mapping: skeleton mapped into the cloud's frame, v * scale + offset with scale {s} and offset {o} "
            "(its input file holds the unmapped coordinates)")


Mapping = tuple[float, Iterable[float]]


def export_ply(
    evaluation: Evaluation,
    out_dir: str | os.PathLike,
    *,
    inputs: Iterable[str | os.PathLike] = (),
    color_by: str = "centeredness",
    binary: bool = True,
    mappings: dict[str, Mapping | None] | None = None,
) -> list[str]:
    """Write the coloured PLY files of ``evaluation`` into ``out_dir`` (created if missing); return
    their paths. Atomic, and never over a loaded input or one of ``inputs`` / the evaluation's inputs.

    ``mappings`` gives, for ``"skeletal"`` and ``"curve"``, the ``(scale, offset)`` that skeleton was
    mapped by into the cloud's frame before it was evaluated (None or the identity: not mapped); the
    files of a mapped one say so in their header (:func:`mapping_comment`).
    """
    if color_by not in COLOR_BY:
        raise ValueError(f"color_by must be one of {', '.join(COLOR_BY)}, got {color_by!r}")
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise SkelInputError("export folder is a file", out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise SkelInputError(f"cannot create export folder ({exc.strerror or exc})", out) from None
    guard = tuple(str(p) for p in inputs if p) + tuple(evaluation._input_paths())
    b_star = evaluation.params.beta_star
    written: list[str] = []

    def mapped(role: str) -> list[str]:
        from ..skeleton_mapping import is_identity

        m = (mappings or {}).get(role)
        if m is None or is_identity(m[0], tuple(m[1])):
            return []
        return [mapping_comment(m[0], m[1])]

    if evaluation.skeletal is not None:
        s = evaluation.skeletal
        values = {
            "boundedness": np.asarray(s.boundedness, dtype=np.float64),
            "centeredness": np.asarray(s.centeredness(b_star), dtype=np.float64),
            "smoothness": np.asarray(s.smoothness, dtype=np.float64),
        }
        path = out / "skeletal.ply"
        write_points_ply(
            path, s.points, scalars=values, colors=map_to_rgb(values[color_by], 0.0, 1.0, COLOUR_MAP),
            inputs=guard, binary=binary, comments=[colour_comment(color_by), *mapped("skeletal")],
        )  # fmt: skip
        written.append(str(path))

    if evaluation.curve is not None:
        c = evaluation.curve
        smooth = np.asarray(c.vertex_smoothness, dtype=np.float64)
        path = out / "curve.ply"
        write_curve_ply(
            path, c.curve.vertices, c.curve.edges,
            scalars={"smoothness": smooth, "degree": np.asarray(c.vertex_degree, dtype=np.int32)},
            colors=map_to_rgb(smooth, 0.0, 1.0, COLOUR_MAP), inputs=guard, binary=binary,
            comments=[colour_comment("smoothness"), *mapped("curve")],
        )  # fmt: skip
        written.append(str(path))

        samples = {
            "boundedness": np.asarray(c.sample_boundedness, dtype=np.float64),
            "centeredness": np.asarray(c.sample_centeredness(b_star), dtype=np.float64),
        }
        by = color_by if color_by in samples else "centeredness"
        path = out / "curve_samples.ply"
        write_points_ply(
            path, c.samples,
            scalars={**samples, "edge": np.asarray(c.sample_edge, dtype=np.int32),
                     "t": np.asarray(c.sample_t, dtype=np.float64)},
            colors=map_to_rgb(samples[by], 0.0, 1.0, COLOUR_MAP), inputs=guard, binary=binary,
            comments=[colour_comment(by), *mapped("curve")],
        )  # fmt: skip
        written.append(str(path))
    return written
