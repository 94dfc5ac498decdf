"""What every reader returns, and the shared parsing helpers (numeric tables, text decoding)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Sequence

import numpy as np

from ..errors import SkelInputError


@dataclass
class RawData:
    """A file's contents before validation: vertices in the file's units, edges when the format has them.

    ``edges`` is None for formats that cannot carry connectivity (XYZ, PCD, NPY); ``curve_format`` is
    True for formats that only ever hold curve skeletons (.cg, SWC, CGAL polylines); ``radius`` is one
    radius per vertex when the file has them (SWC, TreeQSM, a PLY ``radius`` property).
    """

    vertices: np.ndarray
    edges: np.ndarray | None
    format: str
    curve_format: bool = False
    radius: np.ndarray | None = None


def decode_text(data: bytes) -> str:
    """Bytes -> str; undecodable bytes become U+FFFD so the number parser reports the line."""
    text = data.decode("utf-8", errors="replace")
    return text[1:] if text.startswith("\ufeff") else text


def is_comment(line: str) -> bool:
    return line.startswith(("#", "//", "%"))


def split_fields(line: str, delimiter: str | None) -> list[str]:
    if delimiter is None:
        return line.split()
    return [t.strip() for t in line.split(delimiter)]


def _is_float(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


def numeric_table(
    rows: Sequence[tuple[int, str]],
    path: Path,
    *,
    delimiter: str | None = None,
    min_cols: int = 3,
    use_cols: int | None = None,
    what: str = "x y z",
) -> np.ndarray:
    """Parse ``(line_number, text)`` rows of numbers into a float64 array.

    Every row must have the same number of columns (>= ``min_cols``); only the first ``use_cols``
    columns must be numbers (extra columns, e.g. labels, are ignored). The fast path is numpy's
    C parser; on failure a Python scan finds the first bad line for a one-line message.
    """
    if not rows:
        raise SkelInputError(f"no data rows ({what})", path)
    lines = [text for _, text in rows]
    ncols_first = len(split_fields(lines[0], delimiter))
    if ncols_first < min_cols:
        raise SkelInputError(
            f"line {rows[0][0]} has {ncols_first} columns, expected at least {min_cols} ({what})", path
        )
    try:
        # rows is never empty, so loadtxt has nothing to warn about (no warnings filter needed:
        # catch_warnings is not thread-safe and the viewer loads files in a worker thread).
        arr = np.loadtxt(lines, delimiter=delimiter, ndmin=2, dtype=np.float64, comments=None)
        if arr.shape[0] == len(lines) and arr.shape[1] == ncols_first:
            return arr if use_cols is None else arr[:, :use_cols]
    except Exception:
        pass
    return _slow_table(rows, path, delimiter, ncols_first, use_cols or ncols_first, what)


def _slow_table(rows, path, delimiter, ncols, nnum, what) -> np.ndarray:
    """Slow path: report the first row with a wrong column count or a non-number; if there is none
    (numpy only choked on non-numeric extra columns, which are ignored), return the parsed numbers."""
    out = np.empty((len(rows), nnum), dtype=np.float64)
    for k, (lineno, text) in enumerate(rows):
        fields = split_fields(text, delimiter)
        if len(fields) != ncols:
            raise SkelInputError(f"line {lineno} has {len(fields)} columns, expected {ncols} ({what})", path)
        for j in range(nnum):
            if not _is_float(fields[j]):
                token = fields[j] if len(fields[j]) <= 20 else fields[j][:20] + "..."
                raise SkelInputError(f"line {lineno}: {token!r} is not a number ({what})", path)
        out[k] = [float(t) for t in fields[:nnum]]
    return out


def as_edges(array: object, path: Path, what: str = "edges") -> np.ndarray:
    """(E, 2) int64 from any whole-number array; non-integers are an input error."""
    e = np.asarray(array)
    if e.size == 0:
        return np.empty((0, 2), dtype=np.int64)
    if e.dtype == object or e.dtype.kind not in "iufb":
        raise SkelInputError(f"{what} are not numbers", path)
    if e.ndim != 2 or e.shape[1] != 2:
        raise SkelInputError(f"expected {what} as pairs of vertex indices, got shape {e.shape}", path)
    f = e.astype(np.float64)
    if not np.all(np.isfinite(f)) or np.any(f != np.round(f)):
        raise SkelInputError(f"{what} must be whole numbers", path)
    if np.any(np.abs(f) > 2**62):
        raise SkelInputError(f"{what} index out of range", path)
    return f.astype(np.int64)


def as_vertices(array: object, path: Path, what: str = "points") -> np.ndarray:
    """(N, 3) float64 from an (N, >=3) numeric array (extra columns ignored) or an x/y/z record array."""
    a = np.asarray(array)
    if a.dtype.names:
        names = {n.lower(): n for n in a.dtype.names}
        if not all(k in names for k in "xyz"):
            raise SkelInputError(f"record array has no x, y, z fields (fields: {', '.join(a.dtype.names)})", path)
        a = np.column_stack([np.asarray(a[names[k]], dtype=np.float64).ravel() for k in "xyz"])
    if a.dtype == object or a.dtype.kind not in "iufb":
        raise SkelInputError(f"{what} are not numbers (array type {a.dtype})", path)
    if a.ndim == 1 and a.size == 0:
        return np.empty((0, 3), dtype=np.float64)
    if a.ndim != 2 or a.shape[1] < 3:
        raise SkelInputError(f"expected {what} as an N x 3 array, got shape {a.shape}", path)
    return np.ascontiguousarray(a[:, :3], dtype=np.float64)
