"""PLY: clouds, skeletal point sets and curve skeletons (``edge`` element), read and written here.

VTK's PLY reader drops the ``edge`` element and extra properties, so we do not use it. The header is
parsed first and every declared count checked against the file's size before anything is allocated;
the data is then read with numpy in one pass per element: ``np.frombuffer`` for binary rows of fixed
size (a list property of constant length included), numpy's C text parser for ASCII rows, and one
bounded loop over the rows where list lengths vary. Every PLY layout is read (ascii and both binary
byte orders, any scalar and list types, elements in any order, extra elements skipped).

Curve files as written by Open3D's ``write_line_set`` (which pc-skeletor's ``export_results`` uses):
binary little endian, ``double x y z`` vertices, ``element edge`` with ``int vertex1``, ``int
vertex2`` (and ``uchar red green blue`` when the line set is coloured), 0-based indices.
"""

from __future__ import annotations

import io
import os
import re
import struct
from array import array
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Mapping, Union

import numpy as np

from ..errors import SkelInputError
from ._common import RawData, as_edges, numeric_table
from .atomic import atomic_open

_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "i2", "int16": "i2", "ushort": "u2", "uint16": "u2",
    "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
    # numpy's codes, which some writers put in the header too
    "i1": "i1", "u1": "u1", "b1": "u1", "i2": "i2", "u2": "u2", "i4": "i4", "u4": "u4", "f4": "f4", "f8": "f8",
}  # fmt: skip
_STRUCT = {"i1": "b", "u1": "B", "i2": "h", "u2": "H", "i4": "i", "u4": "I"}  # list length types
_VERTEX_NAMES = ("vertex", "vertices", "point", "points")
_EDGE_NAMES = ("edge", "edges", "line", "lines")
_RADIUS_NAMES = ("radius", "radii")
_EDGE_PAIRS = (("vertex1", "vertex2"), ("v1", "v2"), ("vertex_1", "vertex_2"), ("source", "target"))
_NAME_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
# Scalar names that viewers would take for coordinates, colours or normals.
_RESERVED = {"x", "y", "z", "red", "green", "blue", "alpha", "nx", "ny", "nz"}


def is_ply(head: bytes) -> bool:
    return head[:4] in (b"ply\n", b"ply\r") or head[:5] == b"ply \n"


@dataclass(eq=False)
class PlyList:
    """A list property: row ``k`` holds ``lengths[k]`` items, stored one row after the other in
    ``values`` (flat, so that a million faces or polylines need no Python object per row)."""

    lengths: np.ndarray
    values: np.ndarray

    def rows(self) -> list[np.ndarray]:
        """One array per row."""
        return np.split(self.values, np.cumsum(self.lengths)[:-1]) if len(self.lengths) else []


Column = Union[np.ndarray, PlyList]


@dataclass
class _Prop:
    name: str
    code: str  # numpy code of the value ("f4")
    len_code: str | None = None  # numpy code of a list's length; None for a scalar

    @property
    def is_list(self) -> bool:
        return self.len_code is not None


@dataclass
class _Element:
    name: str
    count: int
    props: list[_Prop] = field(default_factory=list)

    @property
    def has_list(self) -> bool:
        return any(p.is_list for p in self.props)

    @property
    def min_row_bytes(self) -> int:
        """Bytes of a binary row whose lists are all empty."""
        return sum(np.dtype(p.len_code or p.code).itemsize for p in self.props)

    def prop(self, *names: str) -> str | None:
        lower = {p.name.lower(): p.name for p in self.props}
        return next((lower[n] for n in names if n in lower), None)

    def get(self, name: str) -> _Prop:
        return next(p for p in self.props if p.name == name)


def _parse_header(data: bytes, path: Path) -> tuple[str, list[_Element], int, int]:
    """(format, elements, byte offset of the data, header lines). Checks every type, and the binary
    counts against the file's size (the ASCII ones against its lines: :func:`_read_ascii`), before any
    data is read, so a flipped digit in ``element vertex 3`` cannot make a reader allocate billions of
    rows. Lines end in LF, CRLF or (a header written on classic Mac OS) CR alone."""
    nl = b"\r" if data[3:4] == b"\r" and data[4:5] != b"\n" else b"\n"
    pos = 0
    fmt = None
    elements: list[_Element] = []
    for lineno in range(1, 100000):
        end = data.find(nl, pos)
        if end < 0:
            raise SkelInputError("PLY header has no end_header line (truncated or not a PLY file)", path)
        line = data[pos:end].decode("ascii", errors="replace").strip()
        pos = end + 1
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
            elements[-1].props.append(_parse_property(parts, lineno, line, path))
        else:
            raise SkelInputError(f"PLY header line {lineno}: unexpected {line[:30]!r}", path)
    else:
        raise SkelInputError("PLY header has no end_header line in its first 100000 lines", path)
    if fmt is None:
        raise SkelInputError("PLY header has no format line", path)
    body = len(data) - pos
    if fmt != "ascii":  # (ASCII rows are lines, counted by _read_ascii)
        need = sum(e.count * e.min_row_bytes for e in elements)
        if need > body:
            raise SkelInputError(f"truncated: PLY header promises at least {need} bytes of data, file has {body}", path)
    return fmt, elements, pos, lineno


def _parse_property(parts: list[str], lineno: int, line: str, path: Path) -> _Prop:
    bad = f"PLY header line {lineno}: bad property line {line[:40]!r}"
    if len(parts) == 5 and parts[1] == "list":
        unknown = [t for t in parts[2:4] if t not in _TYPES]
        if unknown:
            raise SkelInputError(f"{bad} (unknown type {unknown[0][:20]!r})", path)
        if _TYPES[parts[2]] not in _STRUCT:
            raise SkelInputError(f"{bad} (a list length must have an integer type)", path)
        return _Prop(parts[4], _TYPES[parts[3]], _TYPES[parts[2]])
    if len(parts) == 3 and parts[1] != "list":
        if parts[1] not in _TYPES:
            raise SkelInputError(f"{bad} (unknown type {parts[1][:20]!r})", path)
        return _Prop(parts[2], _TYPES[parts[1]])
    raise SkelInputError(bad, path)


def _find(elements: list[_Element], names: tuple[str, ...]) -> _Element | None:
    return next((e for e in elements if e.name.lower() in names), None)


def read_ply(path: Path, data: bytes) -> RawData:
    """The vertices (x y z, a radius when there is one) and the edges (``vertex1``/``vertex2`` pairs or
    polylines) of a PLY file's bytes; other elements and properties are skipped."""
    if not is_ply(data[:8]):
        raise SkelInputError("not a PLY file (does not start with 'ply')", path)
    fmt, elements, start, header_lines = _parse_header(data, path)
    vert = _find(elements, _VERTEX_NAMES)
    if vert is None:
        names = ", ".join(e.name for e in elements) or "none"
        raise SkelInputError(f"PLY file has no vertex element (elements: {names})", path)
    missing = [k for k in "xyz" if vert.prop(k) is None]
    if missing:
        raise SkelInputError(f"PLY vertex element has no {'/'.join(missing)} property", path)
    for k in "xyz":
        if vert.get(vert.prop(k)).is_list:  # type: ignore[arg-type]
            raise SkelInputError(f"PLY vertex property {k} is a list, expected a number", path)
    edge_el = _find(elements, _EDGE_NAMES)
    if edge_el is not None:
        _edge_layout(edge_el, path)  # a file without edge indices fails before its data is read
    wanted = [vert] if edge_el is None else [vert, edge_el]
    tables = _read_elements(fmt, elements, data, start, header_lines, path, wanted)
    v = tables[id(vert)]
    vertices = np.column_stack([np.asarray(v[vert.prop(k)], dtype=np.float64) for k in "xyz"])  # type: ignore[index]
    rname = vert.prop(*_RADIUS_NAMES)
    radius = None
    if rname is not None and not isinstance(v[rname], PlyList):
        radius = np.asarray(v[rname], dtype=np.float64)
    edges = None if edge_el is None else _edges(edge_el, tables[id(edge_el)], path)
    return RawData(vertices=vertices.reshape(-1, 3), edges=edges, format="PLY", radius=radius)


def read_ply_elements(
    path: str | os.PathLike, data: bytes, names: Iterable[str] | None = None
) -> dict[str, dict[str, Column]]:
    """The data of every element of a PLY file (of those in ``names`` when given, compared in lower
    case; the first of two elements with one name), by element and property name: a scalar property as
    a 1-D array (binary: of its declared type; ASCII: float64, the text's values as written), a list
    property as a :class:`PlyList`. For what :class:`RawData` does not carry (a reference's radius)."""
    path = Path(path)
    if not is_ply(data[:8]):
        raise SkelInputError("not a PLY file (does not start with 'ply')", path)
    fmt, elements, start, header_lines = _parse_header(data, path)
    wanted = None if names is None else {n.lower() for n in names}
    chosen: dict[str, _Element] = {}
    for e in elements:
        if e.name not in chosen and (wanted is None or e.name.lower() in wanted):
            chosen[e.name] = e
    tables = _read_elements(fmt, elements, data, start, header_lines, path, list(chosen.values()))
    return {name: tables[id(e)] for name, e in chosen.items()}


# ---- the data -----------------------------------------------------------------------------------


def _read_elements(
    fmt: str, elements: list[_Element], data: bytes, start: int, header_lines: int, path: Path,
    wanted: list[_Element],
) -> dict[int, dict[str, Column]]:  # fmt: skip
    """Columns of the wanted elements, by ``id``; the elements after the last wanted one are not read."""
    if fmt == "ascii":
        return _read_ascii(elements, data, start, header_lines, path, {id(e) for e in wanted})
    order = "<" if fmt == "binary_little_endian" else ">"
    return _read_binary(order, elements, data, start, path, {id(e) for e in wanted})


def _read_binary(
    order: str, elements: list[_Element], data: bytes, offset: int, path: Path, wanted: set[int]
) -> dict[int, dict[str, Column]]:
    out: dict[int, dict[str, Column]] = {}
    for e in elements:
        if not wanted - out.keys():
            break
        keep = id(e) in wanted
        if e.has_list:
            cols, offset = _binary_lists(order, e, data, offset, path)
        else:
            dtype = np.dtype([(f"p{j}", order + p.code) for j, p in enumerate(e.props)])
            if offset + e.count * dtype.itemsize > len(data):
                raise SkelInputError(f"truncated: PLY element '{e.name}' runs past the end of the file", path)
            cols = {}
            if keep and e.props:
                rec = np.frombuffer(data, dtype=dtype, count=e.count, offset=offset)
                cols = {p.name: rec[f"p{j}"] for j, p in enumerate(e.props)}
            offset += e.count * dtype.itemsize
        if keep:
            out[id(e)] = cols
    return out


def _binary_lists(order: str, e: _Element, data: bytes, offset: int, path: Path) -> tuple[dict[str, Column], int]:
    """A binary element with list properties, and the offset after it. The first row's list lengths
    give a fixed row layout; when every row has them (triangles, edges as pairs), one
    ``np.frombuffer`` reads the element, else one loop over the rows finds where each starts."""
    if e.count == 0:
        return _empty(e), offset
    pos, lengths = offset, []
    for p in e.props:
        if p.is_list:
            n = _list_length(order, p, data, pos, e, 0, path)
            lengths.append(n)
            pos += np.dtype(p.len_code).itemsize + n * np.dtype(p.code).itemsize
        else:
            pos += np.dtype(p.code).itemsize
    fields: list[tuple] = []
    it = iter(lengths)
    for j, p in enumerate(e.props):
        if p.is_list:
            fields += [(f"n{j}", order + p.len_code), (f"p{j}", order + p.code, (next(it),))]  # type: ignore[operator]
        else:
            fields.append((f"p{j}", order + p.code))
    if pos > len(data):  # the first row is already cut short
        return _binary_ragged(order, e, data, offset, path)
    dtype = np.dtype(fields)
    if offset + e.count * dtype.itemsize <= len(data):
        rec = np.frombuffer(data, dtype=dtype, count=e.count, offset=offset)
        same = all(np.all(rec[f"n{j}"] == n) for j, n in zip((j for j, p in enumerate(e.props) if p.is_list), lengths))
        if same:
            cols: dict[str, Column] = {}
            for j, p in enumerate(e.props):
                col = rec[f"p{j}"]
                if p.is_list:
                    col = PlyList(np.full(e.count, col.shape[1], dtype=np.int64), col.reshape(-1))
                cols[p.name] = col
            return cols, offset + e.count * dtype.itemsize
    return _binary_ragged(order, e, data, offset, path)


def _list_length(order: str, p: _Prop, data: bytes, pos: int, e: _Element, row: int, path: Path) -> int:
    try:
        (n,) = struct.unpack_from(order + _STRUCT[p.len_code], data, pos)  # type: ignore[index]
    except struct.error:
        raise SkelInputError(f"truncated: PLY element '{e.name}' runs past the end of the file", path) from None
    if n < 0:
        raise SkelInputError(f"PLY element '{e.name}' row {row + 1}: negative length {n} of list '{p.name}'", path)
    return n


def _binary_ragged(order: str, e: _Element, data: bytes, offset: int, path: Path) -> tuple[dict[str, Column], int]:
    """Rows of varying size: a loop over the rows (bounded: the header's count was checked against the
    file's size) records where each run of scalars and each list starts; numpy gathers the values."""
    segments: list[list[_Prop]] = []  # runs of scalars, and each list alone
    for p in e.props:
        if p.is_list or not segments or segments[-1][-1].is_list:
            segments.append([p])
        else:
            segments[-1].append(p)
    plan = []
    for seg in segments:
        if seg[0].is_list:
            p = seg[0]
            unpack = struct.Struct(order + _STRUCT[p.len_code]).unpack_from  # type: ignore[index]
            plan.append((unpack, np.dtype(p.len_code).itemsize, np.dtype(p.code).itemsize))
        else:
            plan.append((None, sum(np.dtype(p.code).itemsize for p in seg), 0))
    starts = [array("q") for _ in segments]  # 8 bytes a row, not a Python int's 36
    lengths = [array("q") for _ in segments]
    end, pos, row = len(data), offset, 0
    try:
        for row in range(e.count):
            for s, (unpack, size, item) in enumerate(plan):
                if unpack is None:
                    starts[s].append(pos)
                    pos += size
                else:
                    (n,) = unpack(data, pos)
                    if n < 0:
                        what = f"PLY element '{e.name}' row {row + 1}"
                        raise SkelInputError(f"{what}: negative length {n} of list '{segments[s][0].name}'", path)
                    pos += size
                    starts[s].append(pos)
                    lengths[s].append(n)
                    pos += n * item
            if pos > end:
                break
    except struct.error:
        pos = end + 1
    if pos > end:
        raise SkelInputError(f"truncated: PLY element '{e.name}' row {row + 1} runs past the end of the file", path)
    cols: dict[str, Column] = {}
    for s, seg in enumerate(segments):
        at = np.asarray(starts[s], dtype=np.int64)
        if seg[0].is_list:
            p = seg[0]
            n = np.asarray(lengths[s], dtype=np.int64)
            item = np.dtype(p.code).itemsize
            first = np.cumsum(n) - n  # index of each row's first item in the flat values
            where = np.repeat(at - first * item, n) + np.arange(int(n.sum()), dtype=np.int64) * item
            cols[p.name] = PlyList(n, _gather(data, where, order + p.code))
        else:
            for p in seg:
                cols[p.name] = _gather(data, at, order + p.code)
                at = at + np.dtype(p.code).itemsize
    return cols, pos


def _gather(data: bytes, where: np.ndarray, code: str) -> np.ndarray:
    """Values of type ``code`` at the byte offsets ``where`` of ``data``: one view of the buffer per
    alignment (offset modulo the item size), indexed."""
    dtype = np.dtype(code)
    size = dtype.itemsize
    out = np.empty(len(where), dtype=dtype)
    residue = where % size
    for r in range(size):
        pick = residue == r
        if pick.any():
            view = np.frombuffer(data, dtype=dtype, offset=r, count=(len(data) - r) // size)
            out[pick] = view[(where[pick] - r) // size]
    return out


def _empty(e: _Element, text: bool = False) -> dict[str, Column]:
    """Columns of an element without rows (of the declared types, float64 for ASCII as when it has rows)."""
    none = np.zeros(0, dtype=np.int64)
    code = (lambda p: "f8") if text else (lambda p: p.code)
    return {p.name: PlyList(none, np.zeros(0, code(p))) if p.is_list else np.zeros(0, code(p)) for p in e.props}


def _read_ascii(
    elements: list[_Element], data: bytes, start: int, header_lines: int, path: Path, wanted: set[int]
) -> dict[int, dict[str, Column]]:
    """One row per line (lists included); each wanted element's lines go to numpy's text parser."""
    if data.find(b"\r", start) >= 0:
        data, start = data[start:].replace(b"\r\n", b"\n").replace(b"\r", b"\n"), 0
    ends = np.flatnonzero(np.frombuffer(data, dtype=np.uint8, offset=start) == 10) + start  # where lines end
    if len(data) > start and not data.endswith(b"\n"):
        ends = np.append(ends, len(data))
    if sum(e.count for e in elements) > len(ends):
        raise SkelInputError("truncated: PLY header promises more rows than the file has lines", path)
    out: dict[int, dict[str, Column]] = {}
    row = 0
    for e in elements:
        if not wanted - out.keys():
            break
        if id(e) in wanted:
            a = int(ends[row - 1]) + 1 if row else start
            b = int(ends[row + e.count - 1]) if e.count else a
            out[id(e)] = _ascii_element(e, data[a:b], header_lines + row + 1, path)
        row += e.count
    return out


def _ascii_element(e: _Element, text: bytes, first_line: int, path: Path) -> dict[str, Column]:
    """The ``e.count`` lines of ``text`` (the first is line ``first_line`` of the file) as columns."""
    if e.count == 0 or not e.props:
        return _empty(e, text=True) if e.count == 0 else {}
    table = None
    if text and not text.isspace():  # (loadtxt warns on no data)
        try:
            parsed = np.loadtxt(io.BytesIO(text), dtype=np.float64, ndmin=2, comments=None)
            if parsed.shape[0] == e.count:  # fewer: loadtxt skipped blank lines
                table = parsed
        except Exception:  # ragged rows or a word: found below, with its line number
            pass
    if not e.has_list:
        if table is None:
            table = numeric_table(_numbered(text, first_line), path, min_cols=len(e.props), what=f"PLY {e.name} row")
        if table.shape[1] != len(e.props):
            raise SkelInputError(f"PLY {e.name} rows have {table.shape[1]} values, header says {len(e.props)}", path)
        return {p.name: table[:, j] for j, p in enumerate(e.props)}
    cols = None if table is None else _ascii_constant_lists(e, table)
    return cols if cols is not None else _ascii_rows(e, text, first_line, path)


def _numbered(text: bytes, first_line: int) -> list[tuple[int, str]]:
    return [(first_line + k, line) for k, line in enumerate(text.decode("utf-8", errors="replace").split("\n"))]


def _ascii_constant_lists(e: _Element, table: np.ndarray) -> dict[str, Column] | None:
    """Columns of a table whose every row has the first row's list lengths, else None."""
    first, col, layout = table[0], 0, []
    for p in e.props:
        n = None
        if p.is_list:
            if col >= len(first) or not (first[col] >= 0 and float(first[col]).is_integer()):
                return None
            n = int(first[col])
        layout.append((p, col, n))
        col += 1 if n is None else 1 + n
    if col != table.shape[1]:
        return None
    cols: dict[str, Column] = {}
    for p, col, n in layout:
        if n is None:
            cols[p.name] = table[:, col]
        elif np.all(table[:, col] == n):
            cols[p.name] = PlyList(np.full(e.count, n, dtype=np.int64), table[:, col + 1 : col + 1 + n].reshape(-1))
        else:
            return None
    return cols


def _ascii_rows(e: _Element, text: bytes, first_line: int, path: Path) -> dict[str, Column]:
    """Rows of varying length, one at a time (bounded by the element's count of lines)."""
    scalars = {p.name: array("d") for p in e.props if not p.is_list}
    lengths = {p.name: array("q") for p in e.props if p.is_list}
    values = {p.name: array("d") for p in e.props if p.is_list}
    what = f"PLY {e.name} row"
    for lineno, line in _numbered(text, first_line):
        tokens = line.split()
        try:
            nums = [float(t) for t in tokens]
        except ValueError:
            bad = next(t for t in tokens if not _is_number(t))
            raise SkelInputError(f"line {lineno}: {bad[:20]!r} is not a number ({what})", path) from None
        col = 0
        for p in e.props:
            if col >= len(nums):
                raise SkelInputError(f"line {lineno} has {len(nums)} values, too few ({what})", path)
            if p.is_list:
                n = nums[col]
                if not (n >= 0 and n.is_integer()):
                    bad = tokens[col][:20]
                    raise SkelInputError(f"line {lineno}: list length {bad!r} of '{p.name}' is not a count", path)
                n = int(n)
                if col + 1 + n > len(nums):
                    raise SkelInputError(f"line {lineno} has {len(nums)} values, too few ({what})", path)
                lengths[p.name].append(n)
                values[p.name].extend(nums[col + 1 : col + 1 + n])
                col += 1 + n
            else:
                scalars[p.name].append(nums[col])
                col += 1
        if col != len(nums):
            raise SkelInputError(f"line {lineno} has {len(nums)} values, expected {col} ({what})", path)
    return {
        p.name: PlyList(np.asarray(lengths[p.name], dtype=np.int64), np.asarray(values[p.name], dtype=np.float64))
        if p.is_list else np.asarray(scalars[p.name], dtype=np.float64)
        for p in e.props
    }  # fmt: skip


def _is_number(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


def _edge_layout(el: _Element, path: Path) -> tuple[str, str] | str:
    """The ``vertex1``/``vertex2`` pair of scalar properties (Open3D, pc-skeletor), else the first list
    property (a polyline per row: consecutive indices become edges)."""
    pair = next(((el.prop(a), el.prop(b)) for a, b in _EDGE_PAIRS if el.prop(a) and el.prop(b)), None)
    if pair is not None:
        for name in pair:
            if el.get(name).is_list:  # type: ignore[arg-type]
                raise SkelInputError(f"PLY {el.name} property {name} is a list, expected a number", path)
        return pair  # type: ignore[return-value]
    lists = [p.name for p in el.props if p.is_list]
    if lists:
        return lists[0]
    raise SkelInputError(
        f"PLY element '{el.name}' has no vertex1/vertex2 properties "
        f"(properties: {', '.join(p.name for p in el.props)})",
        path,
    )


def _edges(el: _Element, cols: dict[str, Column], path: Path) -> np.ndarray:
    layout = _edge_layout(el, path)
    if isinstance(layout, tuple):
        a, b = (np.asarray(cols[n]) for n in layout)
        return as_edges(np.column_stack([a, b]) if len(a) else np.empty((0, 2)), path, "PLY edge indices")
    rows = cols[layout]
    assert isinstance(rows, PlyList)
    flat = rows.values
    if len(flat) < 2:
        return np.empty((0, 2), dtype=np.int64)
    row_of = np.repeat(np.arange(len(rows.lengths)), rows.lengths)
    same = row_of[:-1] == row_of[1:]  # consecutive items of one row
    return as_edges(np.column_stack([flat[:-1][same], flat[1:][same]]), path, "PLY edge indices")


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


def _write(
    path, elements: list[tuple[str, np.ndarray]], inputs: Iterable, binary: bool, comments: Iterable[str] = ()
) -> None:
    """Each (name, record array) pair as an element: the header, then the rows (binary little endian:
    the records' bytes as they are; ASCII: shortest round-tripping text per column type)."""
    lines = ["written by skelcore", *(" ".join(str(c).split()) for c in comments)]  # one line each
    head = ["ply", f"format {'binary_little_endian' if binary else 'ascii'} 1.0", *(f"comment {c}" for c in lines)]
    for name, rec in elements:
        head.append(f"element {name} {len(rec)}")
        head += [f"property {_PLY_TYPE[rec.dtype[n].str[1:]]} {n}" for n in rec.dtype.names]
    head.append("end_header")
    header = ("\n".join(head) + "\n").encode("ascii", errors="backslashreplace")  # a PLY header is ASCII
    if binary:
        with atomic_open(path, "wb", inputs=inputs) as fh:
            fh.write(header)
            for _, rec in elements:
                fh.write(rec.tobytes())  # the fields are little endian already (_vertex_array, write_curve_ply)
        return
    with atomic_open(path, "w", inputs=inputs) as fh:
        fh.write(header.decode("ascii"))
        for _, rec in elements:
            names = rec.dtype.names
            if len(rec) == 0:
                continue
            table = np.column_stack([np.asarray(rec[n], dtype=np.float64) for n in names])
            fmt = " ".join(_TEXT_FMT[rec.dtype[n].str[1:]] for n in names)
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
    _write(path, [("vertex", vertex)], inputs, binary, comments)


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
    _write(path, [("vertex", vertex), ("edge", edge)], inputs, binary, comments)
