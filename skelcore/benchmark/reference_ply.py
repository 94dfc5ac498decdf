"""Read a benchmark reference: a curve skeleton in PLY with an ``edge`` element and an optional
per-vertex ``radius`` property (what :mod:`.writer` writes).

The curve goes through :func:`skelcore.io.load_curve` (every format check and the cleaning of docs/metrics.md 0);
the radius is read beside it and follows the cleaned vertices, since
``skelcore.curve.CurveSkeleton`` has no radius of its own; were it to carry one, with the PLY/SWC
readers reading it, this module would reduce to ``load_curve``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np

from ..curve import CurveSkeleton
from ..errors import SkelInputError
from ..io import load_curve
from ..io.ply import PlyList, is_ply, read_ply_elements

__all__ = ["ReferenceCurve", "read_reference"]


@dataclass(frozen=True)
class ReferenceCurve:
    """A reference curve skeleton and its radius per (cleaned) vertex, None when the file has none."""

    curve: CurveSkeleton
    radius: np.ndarray | None


def read_reference(path: str | os.PathLike) -> ReferenceCurve:
    """The curve and, for a PLY with a vertex ``radius`` property, its radius (finite and > 0, else a
    one-line :class:`SkelInputError` naming the file)."""
    curve = load_curve(path)
    radius = None
    try:
        with open(path, "rb") as fh:
            data = fh.read()
    except OSError as exc:
        raise SkelInputError(f"cannot read the file: {exc.strerror or exc}", path) from None
    if is_ply(data[:8]):
        tables = read_ply_elements(path, data, names=("vertex", "vertices"))
        vertex = next(iter(tables.values()), {})
        names = {name.lower(): name for name in vertex}
        if "radius" in names:
            raw = vertex[names["radius"]]
            if isinstance(raw, PlyList):
                raise SkelInputError("PLY vertex property radius is a list, expected a number", path)
            radius = np.asarray(raw, dtype=np.float64)[curve.vertex_map]
            if not (np.all(np.isfinite(radius)) and np.all(radius > 0)):
                raise SkelInputError("reference radius must be finite and > 0 at every vertex", path)
    return ReferenceCurve(curve, radius)
