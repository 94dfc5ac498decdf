"""Correspondence inputs: a skeletal index file (one 0-based cloud row per skeletal row, NPY or
one integer per line) and CGAL's mean-curvature-flow correspondence output
(``correspondance-poly.polylines.txt``: lines ``2 xs ys zs xp yp zp`` pairing a skeleton vertex
with a surface point), which loads as a skeletal set with its index: surface points are matched
to cloud rows by coordinates (CGAL writes 6 significant digits by default).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from ..errors import SkelInputError
from . import atomic
from ._common import decode_text, is_comment
from .loaders import load_points

__all__ = ["load_skeletal_index", "load_skeletal", "is_cgal_correspondence", "match_cloud_rows"]


def _read(path: str | os.PathLike) -> bytes:
    p = Path(path)
    if not p.exists():
        raise SkelInputError("file not found", p)
    if p.is_dir():
        raise SkelInputError("is a folder, not a file", p)
    atomic.protect(p)
    try:
        return p.read_bytes()
    except OSError as exc:
        raise SkelInputError(f"cannot read file ({exc.strerror or exc})", p) from None


def load_skeletal_index(path: str | os.PathLike, n_skeletal: int, n_cloud: int) -> np.ndarray:
    """(N_s,) int64 cloud rows, checked for count and range (one-line errors naming the file)."""
    data = _read(path)
    if data.startswith(b"\x93NUMPY"):
        import io

        try:
            arr = np.load(io.BytesIO(data), allow_pickle=False)
        except Exception as exc:  # noqa: BLE001 - any parse failure is bad input
            raise SkelInputError(f"malformed NPY file: {' '.join(str(exc).split())[:120]}", path) from None
        if arr.dtype.kind not in "iuf":
            raise SkelInputError(f"skeletal index must hold integers, got {arr.dtype}", path)
        values = arr.ravel()
    else:
        lines = [(i, s.strip()) for i, s in enumerate(decode_text(data).splitlines(), 1)]
        lines = [(i, s) for i, s in lines if s and not is_comment(s)]
        out = np.empty(len(lines), dtype=np.int64)
        for k, (i, s) in enumerate(lines):
            try:
                out[k] = int(s)
            except ValueError:
                raise SkelInputError(f"line {i}: {s[:20]!r} is not a whole number (one cloud row per line)", path) from None
        values = out
    if values.dtype.kind == "f":
        if not np.all(np.isfinite(values)) or np.any(values != np.round(values)):
            raise SkelInputError("skeletal index must hold whole numbers", path)
    values = values.astype(np.int64)
    if len(values) != n_skeletal:
        raise SkelInputError(f"has {len(values)} rows, the skeletal set {n_skeletal}: one cloud row per skeletal point", path)
    if len(values) and (values.min() < 0 or values.max() >= n_cloud):
        bad = int(values.min()) if values.min() < 0 else int(values.max())
        raise SkelInputError(f"cloud row {bad} out of range (the cloud has {n_cloud} rows, 0-based)", path)
    return values


def _correspondence_rows(data: bytes) -> np.ndarray | None:
    """(n, 6) array if every line is ``2 x y z x y z``, else None."""
    rows = [ln.split() for ln in decode_text(data).splitlines() if ln.strip()]
    if not rows or any(len(t) != 7 or t[0] != "2" for t in rows):
        return None
    try:
        return np.array([[float(x) for x in t[1:]] for t in rows], dtype=np.float64)
    except ValueError:
        return None


def is_cgal_correspondence(path: str | os.PathLike) -> bool:
    return _correspondence_rows(_read(path)) is not None


def match_cloud_rows(surface: np.ndarray, cloud: np.ndarray, path: object = None) -> np.ndarray:
    """Cloud row of each surface point, matched by coordinates within the printing precision."""
    dist, idx = cKDTree(cloud).query(surface, k=1, workers=-1)
    scale = max(float(np.abs(cloud).max()), 1e-300)
    tol = 1e-5 * scale  # 6 significant digits (std::ostream's default) of the largest coordinate
    bad = np.flatnonzero(~(dist <= tol))
    if len(bad):
        i = int(bad[0])
        raise SkelInputError(
            f"{len(bad)} of {len(surface)} surface points match no cloud point (first: line {i + 1}, "
            f"{dist[i]:.3g} from the nearest): give the cloud the skeleton was computed from", path,
        )  # fmt: skip
    return idx.astype(np.int64)


def load_skeletal(path: str | os.PathLike, cloud: np.ndarray) -> tuple[np.ndarray, np.ndarray | None, str]:
    """A skeletal set: (points, index or None, format). A CGAL correspondence file gives one
    skeletal row per line (its skeleton vertex) and the index of its surface point's cloud row."""
    data = _read(path)
    rows = _correspondence_rows(data) if b"\x00" not in data[:4096] else None
    if rows is None:
        return load_points(path), None, "points"
    if not np.all(np.isfinite(rows)):
        raise SkelInputError("CGAL correspondence file has NaN or infinite coordinates", path)
    return rows[:, :3].copy(), match_cloud_rows(rows[:, 3:], cloud, path), "CGAL correspondence"
