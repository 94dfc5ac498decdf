"""PLY: clouds, skeletal point sets and curve skeletons (``edge`` element), read with plyfile.

VTK's PLY reader drops the ``edge`` element and extra properties, so we use plyfile. Curve files as
written by Open3D's ``write_line_set`` (used by pc-skeletor's ``export_results``): binary little
endian, ``double x y z`` vertices, ``element edge`` with ``int vertex1``, ``int vertex2`` (and
``uchar red green blue`` when the line set is coloured), 0-based indices.
"""

from __future__ import annotations

import io
import os
import re
from pathlib import Path
from typing import Iterable, Mapping

import numpy as np
from plyfile import PlyData, PlyElement

from ..errors import SkelInputError
from ._common import RawData, as_edges
from .atomic import atomic_open

_SIZES = {
    "char": 1, "int8": 1, "uchar": 1, "uint8": 1,
    "short": 2, "int16": 2, "ushort": 2, "uint16": 2,
    "int": 4, "int32": 4, "uint": 4, "uint32": 4,
    "float": 4, "float32": 4, "double": 8, "float64": 8,
}  # fmt: skip
_VERTEX_NAMES = ("vertex", "vertices", "point", "points")
_EDGE_NAMES = ("edge", "edges", "line", "lines")
_NAME_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


def is_ply(head: bytes) -> bool:
    return head[:4] in (b"ply\n", b"ply\r") or head[:5] == b"ply \n"


def _check_header(data: bytes, path: Path) -> None:
    """Check the header's element sizes against the file size before plyfile allocates anything.

    A flipped digit in ``element vertex 3`` would otherwise make plyfile try to read (or allocate)
    billions of rows.
    """
    end = data.find(b"end_header")
    if end < 0:
        raise SkelInputError("PLY header has no end_header line (truncated or not a PLY file)", path)
    nl = data.find(b"\n", end)
    if nl < 0:
        raise SkelInputError("PLY file ends right after its header (truncated)", path)
    body_size = len(data) - nl - 1
    header = data[:end].decode("ascii", errors="replace").splitlines()
    fmt = None
    counts: list[int] = []
    row_sizes: list[int | None] = []
    for line in header:
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "format" and len(parts) >= 2:
            fmt = parts[1]
        elif parts[0] == "element" and len(parts) >= 3:
            try:
                counts.append(int(parts[2]))
            except ValueError:
                raise SkelInputError(f"PLY header: bad element count {parts[2][:20]!r}", path) from None
            if counts[-1] < 0:
                raise SkelInputError(f"PLY header: negative element count {counts[-1]}", path)
            row_sizes.append(0)
        elif parts[0] == "property" and row_sizes:
            if len(parts) >= 2 and parts[1] == "list":
                row_sizes[-1] = None  # variable-size rows: cannot pre-check
            elif row_sizes[-1] is not None and len(parts) >= 2:
                size = _SIZES.get(parts[1])
                if size is None:
                    raise SkelInputError(f"PLY header: unknown property type {parts[1][:20]!r}", path)
                row_sizes[-1] += size
    if fmt is None:
        raise SkelInputError("PLY header has no format line", path)
    if fmt == "ascii":
        n_lines = data.count(b"\n", nl + 1) + 1
        if sum(counts) > n_lines:
            raise SkelInputError(
                f"truncated: PLY header promises {sum(counts)} rows, file has {n_lines} lines of data", path
            )
    elif fmt in ("binary_little_endian", "binary_big_endian"):
        if all(s is not None for s in row_sizes):
            need = sum(c * s for c, s in zip(counts, row_sizes))  # type: ignore[operator]
            if need > body_size:
                raise SkelInputError(
                    f"truncated: PLY header promises {need} bytes of data, file has {body_size}", path
                )
        elif sum(counts) > body_size:
            raise SkelInputError("truncated: PLY header promises more rows than the file has bytes", path)
    else:
        raise SkelInputError(f"unknown PLY format {fmt[:30]!r}", path)


def _element(ply: PlyData, names: tuple[str, ...]):
    for el in ply.elements:
        if el.name.lower() in names:
            return el
    return None


def read_ply(path: Path, data: bytes) -> RawData:
    if not is_ply(data[:8]):
        raise SkelInputError("not a PLY file (does not start with 'ply')", path)
    _check_header(data, path)
    ply = PlyData.read(io.BytesIO(data), mmap=False)
    vert = _element(ply, _VERTEX_NAMES)
    if vert is None:
        names = ", ".join(el.name for el in ply.elements) or "none"
        raise SkelInputError(f"PLY file has no vertex element (elements: {names})", path)
    props = {p.name.lower(): p.name for p in vert.properties}
    missing = [k for k in "xyz" if k not in props]
    if missing:
        raise SkelInputError(f"PLY vertex element has no {'/'.join(missing)} property", path)
    cols = []
    for k in "xyz":
        col = np.asarray(vert.data[props[k]])
        if col.dtype == object:
            raise SkelInputError(f"PLY vertex property {k} is a list, expected a number", path)
        cols.append(col.astype(np.float64))
    vertices = np.column_stack(cols) if len(vert.data) else np.empty((0, 3))
    edges = None
    edge_el = _element(ply, _EDGE_NAMES)
    if edge_el is not None:
        edges = _ply_edges(edge_el, path)
    return RawData(vertices=vertices, edges=edges, format="PLY")


def _ply_edges(el, path: Path) -> np.ndarray:
    """``vertex1``/``vertex2`` scalar properties (Open3D, pc-skeletor), or one list property per row
    (a polyline: consecutive indices become edges)."""
    props = {p.name.lower(): p.name for p in el.properties}
    for a, b in (("vertex1", "vertex2"), ("v1", "v2"), ("vertex_1", "vertex_2"), ("source", "target")):
        if a in props and b in props:
            if len(el.data) == 0:
                return np.empty((0, 2), dtype=np.int64)
            pairs = np.column_stack([np.asarray(el.data[props[a]]), np.asarray(el.data[props[b]])])
            return as_edges(pairs, path, "PLY edge indices")
    lists = [p.name for p in el.properties if getattr(p, "len_dtype", None) is not None]
    if lists:
        out = []
        for row in el.data[lists[0]]:
            row = np.asarray(row, dtype=np.int64).ravel()
            if len(row) >= 2:
                out.append(np.column_stack([row[:-1], row[1:]]))
        return np.concatenate(out) if out else np.empty((0, 2), dtype=np.int64)
    raise SkelInputError(
        f"PLY element '{el.name}' has no vertex1/vertex2 properties "
        f"(properties: {', '.join(p.name for p in el.properties)})",
        path,
    )


# ---- writers ------------------------------------------------------------------------------------


def _vertex_array(
    points: np.ndarray, scalars: Mapping[str, np.ndarray], colors: np.ndarray | None
) -> np.ndarray:
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise ValueError(f"points must be N x 3, got shape {pts.shape}")
    n = len(pts)
    fields: list[tuple[str, str]] = [("x", "<f8"), ("y", "<f8"), ("z", "<f8")]
    if colors is not None:
        col = np.asarray(colors)
        if col.shape != (n, 3):
            raise ValueError(f"colors must be N x 3 (N = {n}), got shape {col.shape}")
        if col.dtype.kind == "f":
            raise ValueError("colors must be integers 0..255 (use skelcore.colors.map_to_rgb)")
        fields += [("red", "u1"), ("green", "u1"), ("blue", "u1")]
    values: dict[str, np.ndarray] = {}
    for name, val in scalars.items():
        if not _NAME_RE.match(name) or name.lower() in {f[0] for f in fields}:
            raise ValueError(f"bad PLY property name {name!r}")
        arr = np.asarray(val).ravel()
        if arr.shape != (n,):
            raise ValueError(f"scalar {name!r} has {arr.size} values for {n} points")
        # Integer quantities (degree, edge index) stay integers; everything else is a float property.
        kind = "<i4" if arr.dtype.kind in "iub" else "<f4"
        fields.append((name, kind))
        values[name] = arr
    out = np.empty(n, dtype=fields)
    out["x"], out["y"], out["z"] = pts[:, 0], pts[:, 1], pts[:, 2]
    if colors is not None:
        col = np.asarray(colors)
        if n and (col.min() < 0 or col.max() > 255):
            raise ValueError("colors must be in 0..255")
        out["red"], out["green"], out["blue"] = col[:, 0], col[:, 1], col[:, 2]
    for name, arr in values.items():
        out[name] = arr
    return out


def _write(path, elements: list[PlyElement], inputs: Iterable, binary: bool) -> None:
    ply = PlyData(elements, text=not binary, byte_order="<", comments=["written by skelcore"])
    with atomic_open(path, "wb", inputs=inputs) as fh:
        ply.write(fh)


def write_points_ply(
    path: str | os.PathLike,
    points: np.ndarray,
    *,
    scalars: Mapping[str, np.ndarray] | None = None,
    colors: np.ndarray | None = None,
    inputs: Iterable[str | os.PathLike] = (),
    binary: bool = True,
) -> None:
    """Point set as PLY: ``double x y z``, ``uchar red green blue`` when ``colors`` (N x 3, 0..255) is
    given, one ``float`` property per scalar (NaN kept as NaN, SPEC 5). Atomic; never overwrites an input.
    """
    vertex = _vertex_array(points, scalars or {}, colors)
    _write(path, [PlyElement.describe(vertex, "vertex")], inputs, binary)


def write_curve_ply(
    path: str | os.PathLike,
    vertices: np.ndarray,
    edges: np.ndarray,
    *,
    scalars: Mapping[str, np.ndarray] | None = None,
    colors: np.ndarray | None = None,
    inputs: Iterable[str | os.PathLike] = (),
    binary: bool = True,
) -> None:
    """Curve skeleton as PLY: the vertices as in :func:`write_points_ply` plus an ``edge`` element with
    ``int vertex1 vertex2`` (0-based), the layout Open3D's LineSet writer uses, so Open3D, MeshLab
    and pc-skeletor's tooling read it back."""
    vertex = _vertex_array(vertices, scalars or {}, colors)
    e = np.asarray(edges)
    if e.size == 0:
        e = np.empty((0, 2), dtype=np.int64)
    if e.ndim != 2 or e.shape[1] != 2:
        raise ValueError(f"edges must be E x 2, got shape {e.shape}")
    if e.size and (e.min() < 0 or e.max() >= len(vertex)):
        raise ValueError("edge index out of range")
    edge = np.empty(len(e), dtype=[("vertex1", "<i4"), ("vertex2", "<i4")])
    edge["vertex1"], edge["vertex2"] = e[:, 0], e[:, 1]
    _write(path, [PlyElement.describe(vertex, "vertex"), PlyElement.describe(edge, "edge")], inputs, binary)
