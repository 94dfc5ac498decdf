"""PLY: clouds, skeletal point sets and curve skeletons (``edge`` element).

VTK's PLY reader drops the ``edge`` element and extra properties, so we do not use it. The header is
parsed here and the data read with numpy in one pass (``np.frombuffer`` for binary, the C text
parser for ASCII), because plyfile reads non-memory-mapped binary and all ASCII data row by row in
Python (seconds per million points); plyfile remains the reader for the rare layouts the fast path
does not cover (a list property in the vertex or edge element, or a list element before them) and
writes our PLY files.

Curve files as written by Open3D's ``write_line_set`` (which pc-skeletor's ``export_results`` uses):
binary little endian, ``double x y z`` vertices, ``element edge`` with ``int vertex1``, ``int
vertex2`` (and ``uchar red green blue`` when the line set is coloured), 0-based indices.
"""

from __future__ import annotations

import io
import os
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Mapping

import numpy as np
from plyfile import PlyData, PlyElement

from ..errors import SkelInputError
from ._common import RawData, as_edges, numeric_table
from .atomic import atomic_open

_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "i2", "int16": "i2", "ushort": "u2", "uint16": "u2",
    "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}  # fmt: skip
_VERTEX_NAMES = ("vertex", "vertices", "point", "points")
_EDGE_NAMES = ("edge", "edges", "line", "lines")
_RADIUS_NAMES = ("radius", "radii")
_EDGE_PAIRS = (("vertex1", "vertex2"), ("v1", "v2"), ("vertex_1", "vertex_2"), ("source", "target"))
_NAME_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
# Scalar names that viewers would take for coordinates, colours or normals.
_RESERVED = {"x", "y", "z", "red", "green", "blue", "alpha", "nx", "ny", "nz"}


def is_ply(head: bytes) -> bool:
    return head[:4] in (b"ply\n", b"ply\r") or head[:5] == b"ply \n"


@dataclass
class _Element:
    name: str
    count: int
    props: list[tuple[str, str]] = field(default_factory=list)  # (name, numpy code or "list")

    @property
    def has_list(self) -> bool:
        return any(t == "list" for _, t in self.props)

    def prop(self, *names: str) -> str | None:
        lower = {n.lower(): n for n, _ in self.props}
        return next((lower[n] for n in names if n in lower), None)


def _parse_header(data: bytes, path: Path) -> tuple[str, list[_Element], int]:
    """(format, elements, byte offset of the data). Checks every count and type before any data
    is read, so a flipped digit in ``element vertex 3`` cannot make a reader allocate billions of rows."""
    pos = 0
    fmt = None
    elements: list[_Element] = []
    for lineno in range(1, 100000):
        nl = data.find(b"\n", pos)
        if nl < 0:
            raise SkelInputError("PLY header has no end_header line (truncated or not a PLY file)", path)
        line = data[pos:nl].decode("ascii", errors="replace").strip()
        pos = nl + 1
        parts = line.split()
        if not parts or parts[0] in ("comment", "obj_info") or lineno == 1:
            continue
        key = parts[0]
        if key == "end_header":
            break
        if key == "format":
            if len(parts) < 2 or parts[1] not in ("ascii", "binary_little_endian", "binary_big_endian"):
                raise SkelInputError(f"unknown PLY format {' '.join(parts[1:])[:30]!r}", path)
            fmt = parts[1]
        elif key == "element":
            if len(parts) != 3 or not parts[2].isdigit():
                raise SkelInputError(f"PLY header line {lineno}: bad element line {line[:40]!r}", path)
            elements.append(_Element(parts[1], int(parts[2])))
        elif key == "property":
            if not elements:
                raise SkelInputError(f"PLY header line {lineno}: property before any element", path)
            if len(parts) == 5 and parts[1] == "list" and parts[2] in _TYPES and parts[3] in _TYPES:
                elements[-1].props.append((parts[4], "list"))
            elif len(parts) == 3 and parts[1] in _TYPES:
                elements[-1].props.append((parts[2], _TYPES[parts[1]]))
            else:
                raise SkelInputError(f"PLY header line {lineno}: bad property line {line[:40]!r}", path)
        else:
            raise SkelInputError(f"PLY header line {lineno}: unexpected {line[:30]!r}", path)
    else:
        raise SkelInputError("PLY header has no end_header line in its first 100000 lines", path)
    if fmt is None:
        raise SkelInputError("PLY header has no format line", path)
    body = len(data) - pos
    if fmt == "ascii":
        if sum(e.count for e in elements) > data.count(b"\n", pos) + 1:
            raise SkelInputError("truncated: PLY header promises more rows than the file has lines", path)
    else:
        need = 0
        for e in elements:
            if e.has_list:
                need += e.count  # at least one byte (the list length) per row
            else:
                need += e.count * sum(np.dtype(t).itemsize for _, t in e.props)
        if need > body:
            raise SkelInputError(f"truncated: PLY header promises at least {need} bytes of data, file has {body}", path)
    return fmt, elements, pos


def _find(elements: list[_Element], names: tuple[str, ...]) -> _Element | None:
    return next((e for e in elements if e.name.lower() in names), None)


def read_ply(path: Path, data: bytes) -> RawData:
    if not is_ply(data[:8]):
        raise SkelInputError("not a PLY file (does not start with 'ply')", path)
    fmt, elements, start = _parse_header(data, path)
    vert = _find(elements, _VERTEX_NAMES)
    if vert is None:
        names = ", ".join(e.name for e in elements) or "none"
        raise SkelInputError(f"PLY file has no vertex element (elements: {names})", path)
    missing = [k for k in "xyz" if vert.prop(k) is None]
    if missing:
        raise SkelInputError(f"PLY vertex element has no {'/'.join(missing)} property", path)
    edge_el = _find(elements, _EDGE_NAMES)
    pair = None if edge_el is None else next(
        ((edge_el.prop(a), edge_el.prop(b)) for a, b in _EDGE_PAIRS if edge_el.prop(a) and edge_el.prop(b)), None
    )
    fast_edges = edge_el is None or (not edge_el.has_list and pair is not None)
    if not vert.has_list and fast_edges:
        tables = _read_fast(fmt, elements, data, start, path, wanted={id(vert), id(edge_el)})
        if tables is not None:
            v = tables[id(vert)]
            vertices = np.column_stack([np.asarray(v[vert.prop(k)], dtype=np.float64) for k in "xyz"])
            rname = vert.prop(*_RADIUS_NAMES)
            radius = None if rname is None else np.asarray(v[rname], dtype=np.float64)
            edges = None
            if edge_el is not None:
                e = tables[id(edge_el)]
                a, b = pair  # type: ignore[misc]
                pairs = np.column_stack([np.asarray(e[a]), np.asarray(e[b])]) if len(e[a]) else np.empty((0, 2))
                edges = as_edges(pairs, path, "PLY edge indices")
            return RawData(vertices=vertices.reshape(-1, 3), edges=edges, format="PLY", radius=radius)
    return _read_plyfile(path, data)


def _read_fast(fmt, elements, data, start, path, wanted) -> dict[int, dict[str, np.ndarray]] | None:
    """Column arrays of the wanted elements, or None when a list element precedes one of them."""
    out: dict[int, dict[str, np.ndarray]] = {}
    wanted = {w for w in wanted if w != id(None)}
    if fmt == "ascii":
        lines = data[start:].decode("utf-8", errors="replace").splitlines()
        header_lines = data.count(b"\n", 0, start)
        row = 0
        for e in elements:
            if not wanted - set(out):
                break
            if id(e) in wanted:
                first_line = header_lines + row + 1
                rows = [(first_line + k, text) for k, text in enumerate(lines[row : row + e.count])]
                if len(rows) < e.count:
                    raise SkelInputError(f"truncated: PLY element '{e.name}' has {len(rows)} of {e.count} rows", path)
                if e.count:
                    table = numeric_table(rows, path, min_cols=len(e.props), what=f"PLY {e.name} row")
                else:
                    table = np.empty((0, len(e.props)))
                if table.shape[1] != len(e.props):
                    raise SkelInputError(
                        f"PLY {e.name} rows have {table.shape[1]} values, header says {len(e.props)}", path
                    )
                out[id(e)] = {name: table[:, j] for j, (name, _) in enumerate(e.props)}
            row += e.count  # ASCII PLY: one row per line, lists included
        return out
    order = "<" if fmt == "binary_little_endian" else ">"
    offset = start
    for e in elements:
        if not wanted - set(out):
            break
        if e.has_list:
            return None  # row sizes unknown: let plyfile walk it
        dtype = np.dtype([(f"p{j}", order + t) for j, (_, t) in enumerate(e.props)])
        if id(e) in wanted:
            if offset + e.count * dtype.itemsize > len(data):
                raise SkelInputError(f"truncated: PLY element '{e.name}' runs past the end of the file", path)
            rec = np.frombuffer(data, dtype=dtype, count=e.count, offset=offset)
            out[id(e)] = {name: rec[f"p{j}"] for j, (name, _) in enumerate(e.props)}
        offset += e.count * dtype.itemsize
    return out


def _read_plyfile(path: Path, data: bytes) -> RawData:
    ply = PlyData.read(io.BytesIO(data), mmap=False)
    vert = next((el for el in ply.elements if el.name.lower() in _VERTEX_NAMES), None)
    assert vert is not None  # checked on our own header parse
    props = {p.name.lower(): p.name for p in vert.properties}
    cols = []
    for k in "xyz":
        col = np.asarray(vert.data[props[k]])
        if col.dtype == object:
            raise SkelInputError(f"PLY vertex property {k} is a list, expected a number", path)
        cols.append(col.astype(np.float64))
    vertices = np.column_stack(cols) if len(vert.data) else np.empty((0, 3))
    rname = next((props[k] for k in _RADIUS_NAMES if k in props), None)
    radius = None
    if rname is not None and np.asarray(vert.data[rname]).dtype != object:
        radius = np.asarray(vert.data[rname], dtype=np.float64)
    edges = None
    edge_el = next((el for el in ply.elements if el.name.lower() in _EDGE_NAMES), None)
    if edge_el is not None:
        edges = _ply_edges(edge_el, path)
    return RawData(vertices=vertices, edges=edges, format="PLY", radius=radius)


def _ply_edges(el, path: Path) -> np.ndarray:
    """``vertex1``/``vertex2`` scalar properties (Open3D, pc-skeletor), or one list property per row
    (a polyline: consecutive indices become edges)."""
    props = {p.name.lower(): p.name for p in el.properties}
    for a, b in _EDGE_PAIRS:
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
        if not _NAME_RE.match(name) or name.lower() in _RESERVED:
            raise ValueError(f"bad PLY property name {name!r}")
        arr = np.asarray(val).ravel()
        if arr.shape != (n,):
            raise ValueError(f"scalar {name!r} has {arr.size} values for {n} points")
        # Integer quantities (degree, edge index) stay integers; a radius is a double (round trips
        # exactly); everything else is a float property.
        kind = "<i4" if arr.dtype.kind in "iub" else "<f8" if name in _RADIUS_NAMES else "<f4"
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


_PLY_TYPE = {"f8": "double", "f4": "float", "i4": "int", "u1": "uchar"}
_TEXT_FMT = {"f8": "%.17g", "f4": "%.9g", "i4": "%d", "u1": "%d"}


def _write(path, elements: list[PlyElement], inputs: Iterable, binary: bool, comments: Iterable[str] = ()) -> None:
    lines = ["written by skelcore", *(" ".join(str(c).split()) for c in comments)]  # one line each
    if binary:
        ply = PlyData(elements, text=False, byte_order="<", comments=lines)
        with atomic_open(path, "wb", inputs=inputs) as fh:
            ply.write(fh)
        return
    # ASCII by hand: plyfile formats text one row at a time (~20 s per million points).
    head = ["ply", "format ascii 1.0", *(f"comment {c}" for c in lines)]
    for el in elements:
        head.append(f"element {el.name} {len(el.data)}")
        head += [f"property {_PLY_TYPE[el.data.dtype[n].str[1:]]} {n}" for n in el.data.dtype.names]
    head.append("end_header")
    with atomic_open(path, "w", inputs=inputs) as fh:
        fh.write("\n".join(head) + "\n")
        for el in elements:
            names = el.data.dtype.names
            if len(el.data) == 0:
                continue
            table = np.column_stack([np.asarray(el.data[n], dtype=np.float64) for n in names])
            fmt = " ".join(_TEXT_FMT[el.data.dtype[n].str[1:]] for n in names)
            np.savetxt(fh, table, fmt=fmt)


def write_points_ply(
    path: str | os.PathLike,
    points: np.ndarray,
    *,
    scalars: Mapping[str, np.ndarray] | None = None,
    colors: np.ndarray | None = None,
    inputs: Iterable[str | os.PathLike] = (),
    binary: bool = True,
    comments: Iterable[str] = (),
) -> None:
    """Point set as PLY: ``double x y z``, ``uchar red green blue`` when ``colors`` (N x 3, 0..255) is
    given, one ``float`` property per scalar (NaN kept as NaN, docs/metrics.md 5.5), each of ``comments`` as a
    header comment line. Atomic; never overwrites an input.
    """
    vertex = _vertex_array(points, scalars or {}, colors)
    _write(path, [PlyElement.describe(vertex, "vertex")], inputs, binary, comments)


def write_curve_ply(
    path: str | os.PathLike,
    vertices: np.ndarray,
    edges: np.ndarray,
    *,
    scalars: Mapping[str, np.ndarray] | None = None,
    colors: np.ndarray | None = None,
    inputs: Iterable[str | os.PathLike] = (),
    binary: bool = True,
    comments: Iterable[str] = (),
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
    _write(path, [PlyElement.describe(vertex, "vertex"), PlyElement.describe(edge, "edge")], inputs, binary, comments)
