"""Lossless conversion between formats (``skelcore convert``): read any curve or point set, write it in
the output's format, read the written file back and compare (vertex and edge counts, components,
cycles, the largest coordinate and radius change). A target that cannot hold the input (a cycle in
SWC, radii in OBJ, edges in XYZ) is refused with the reason unless ``lossy``; the input is never
overwritten and an existing output is replaced only with ``force``. With ``scale`` and ``offset`` the
coordinates are written mapped into another frame, ``v * scale + offset`` (a radius times ``scale``), the
map of ``skelcore evaluate --skeleton-scale/--skeleton-offset`` (``skelcore.skeleton_mapping``), so a
skeleton in a tool's own frame becomes a file in its cloud's (docs/guide/cli.md, ``skelcore convert``).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..curve import CurveSkeleton
from ..errors import SkelInputError
from ..skeleton_mapping import check_mapping, is_identity
from . import atomic
from .loaders import Loaded, load_any, load_curve, load_points
from .writers import CURVE_SUFFIXES, POINT_SUFFIXES, curve_loss, points_loss, write_curve, write_point_set

__all__ = ["Described", "Conversion", "convert_file", "describe"]


@dataclass(frozen=True)
class Described:
    """What a file holds, as compared before and after: kind, counts, and whether radii are known."""

    kind: str
    format: str
    n_vertices: int
    n_edges: int
    components: int
    cycles: int
    has_radius: bool

    def line(self) -> str:
        if self.kind == "points":
            return f"{self.format}: point set, {self.n_vertices} points"
        return (f"{self.format}: curve, {self.n_vertices} vertices, {self.n_edges} edges, {self.components} "
                f"component{'s' * (self.components != 1)}, {self.cycles} cycle{'s' * (self.cycles != 1)}"
                f"{', radii' if self.has_radius else ''}")


@dataclass(frozen=True)
class Conversion:
    """The result of :func:`convert_file`: both descriptions, the largest changes, what was lost."""

    source: Described
    written: Described
    max_coordinate_change: float
    max_radius_change: float | None
    lossy_reason: str | None

    @property
    def same(self) -> bool:
        a, b = self.source, self.written
        return (a.kind, a.n_vertices, a.n_edges, a.components, a.cycles, a.has_radius) == \
            (b.kind, b.n_vertices, b.n_edges, b.components, b.cycles, b.has_radius) and \
            self.max_coordinate_change == 0.0 and not self.max_radius_change


def describe(loaded: Loaded) -> Described:
    """Kind, counts, components and independent cycles (E - V + C) of a loaded file."""
    if loaded.kind == "points":
        n = len(loaded.points)
        return Described("points", loaded.format, n, 0, n, 0, False)
    from ..metrics.reference import graph_counts

    c = loaded.curve
    counts = graph_counts(c)
    return Described("curve", loaded.format, c.n_vertices, c.n_edges, counts["components"], counts["cycles"],
                     c.radius is not None)


def _vertices(loaded: Loaded) -> np.ndarray:
    return loaded.points if loaded.kind == "points" else loaded.curve.vertices


def _largest_change(a: np.ndarray, b: np.ndarray) -> float:
    """Row by row when the counts agree (every writer keeps the order), else the Hausdorff distance."""
    if a.shape == b.shape:
        return float(np.abs(a - b).max()) if a.size else 0.0
    from scipy.spatial import cKDTree

    return float(max(cKDTree(b).query(a)[0].max(), cKDTree(a).query(b)[0].max()))


def convert_file(source: str | os.PathLike, target: str | os.PathLike, *, lossy: bool = False, force: bool = False,
                 as_kind: str | None = None, binary: bool = True, scale: float = 1.0,
                 offset: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> Conversion:
    """Convert ``source`` to ``target``'s format (by its extension), mapped by ``v * scale + offset``,
    then read ``target`` back and compare with what was meant to be written. SkelInputError (one line)
    for an unreadable input, an unwritable or lossy target, a scale or offset that is not finite."""
    try:
        scale, offset = check_mapping(scale, offset)
    except ValueError as exc:
        raise SkelInputError(f"--skeleton-scale/--skeleton-offset: {exc}") from None
    src, dst = Path(source), Path(target)
    if src.exists() and dst.exists() and src.resolve() == dst.resolve():
        raise SkelInputError("is the input: convert never overwrites its input", dst)
    if dst.exists() and not force:
        raise SkelInputError("exists: give --force to replace it", dst)
    suffix = dst.suffix.lower()
    writable = sorted(set(CURVE_SUFFIXES) | set(POINT_SUFFIXES))
    if suffix not in writable:
        raise SkelInputError(f"cannot write {suffix or '(no extension)'} files (writable: {', '.join(writable)})", dst)
    if as_kind == "curve":
        c = load_curve(source)
        loaded = Loaded(kind="curve", path=str(source), format=_format_of(source), curve=c)
    elif as_kind == "points":
        loaded = Loaded(kind="points", path=str(source), format=_format_of(source), points=load_points(source))
    else:
        loaded = load_any(source)
    before = describe(loaded)
    if not is_identity(scale, offset):
        loaded = _mapped(loaded, scale, np.asarray(offset))
    reason = curve_loss(dst, loaded.curve) if loaded.kind == "curve" else points_loss(dst)
    if reason is not None and loaded.kind == "points":
        raise SkelInputError(reason, dst)
    if reason is not None and not lossy:
        raise SkelInputError(f"{reason} (give --lossy to write it anyway)", dst)
    try:
        if loaded.kind == "curve":
            write_curve(dst, loaded.curve, inputs=(source,), binary=binary, lossy=lossy)
        else:
            write_point_set(dst, loaded.points, inputs=(source,), binary=binary)
    except ValueError as exc:
        if isinstance(exc, SkelInputError):
            raise
        raise SkelInputError(str(exc), dst) from None
    back = load_any(dst)
    atomic.release(dst)  # reading it back protected it: it is our output, not an input
    if loaded.kind == "curve" and back.kind == "points" and before.n_edges == 0:
        back = Loaded(kind="curve", path=str(dst), format=back.format,
                      curve=CurveSkeleton.from_raw(back.points, np.empty((0, 2))))
    after = describe(back)
    r_change = None
    if loaded.kind == "curve" and back.kind == "curve" and loaded.curve.radius is not None \
            and back.curve.radius is not None and loaded.curve.n_vertices == back.curve.n_vertices:
        diff = np.abs(loaded.curve.radius - back.curve.radius)
        both_nan = np.isnan(loaded.curve.radius) & np.isnan(back.curve.radius)
        r_change = float(np.where(both_nan, 0.0, diff).max())
        r_change = math.inf if math.isnan(r_change) else r_change
    return Conversion(before, after, _largest_change(_vertices(loaded), _vertices(back)), r_change, reason)


def _mapped(loaded: Loaded, scale: float, offset: np.ndarray) -> Loaded:
    """The loaded file's coordinates ``* scale + offset`` (a curve's radius ``* scale``)."""
    if loaded.kind == "points":
        return Loaded(kind="points", path=loaded.path, format=loaded.format, points=loaded.points * scale + offset)
    curve = loaded.curve.transformed(lambda v: v * scale + offset, radius_scale=scale)
    return Loaded(kind="curve", path=loaded.path, format=loaded.format, curve=curve)


def _format_of(path: str | os.PathLike) -> str:
    from .loaders import detect_format

    p = Path(path)
    try:
        with open(p, "rb") as fh:
            return detect_format(p, fh.read(8192)).upper()
    except OSError:
        return p.suffix.lstrip(".").upper()
