"""Text formats: XYZ/TXT/CSV/PTS tables, OBJ, OFF, the .cg curve graph, CGAL polylines, PyGEL graphs
(SWC: :mod:`.swc`); the OBJ and .cg curve writers."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from ..errors import SkelInputError
from ._common import RawData, decode_text, is_comment, numeric_table, split_fields

_MAX_HEADER_LINES = 100


def _rows(text: str, start: int = 0) -> list[tuple[int, str]]:
    """Non-empty, non-comment lines as (1-based line number, stripped text), from line ``start``."""
    out = []
    for i, line in enumerate(text.splitlines()[start:], start + 1):
        s = line.strip()
        if s and not is_comment(s):
            out.append((i, s))
    return out


def _delimiter(line: str) -> str | None:
    for d in (",", ";"):
        if d in line:
            return d
    return None


def _leading_numbers(fields: list[str], n: int) -> bool:
    if len(fields) < n:
        return False
    try:
        for t in fields[:n]:
            float(t)
    except ValueError:
        return False
    return True


# ---- XYZ / TXT / CSV / PTS ----------------------------------------------------------------------


def read_xyz(path: Path, data: bytes) -> RawData:
    """One point per row, x y z first (whitespace, comma or semicolon separated, extra columns
    ignored); header lines before the first numeric row are skipped; a lone integer row is a PTS
    point-count line (checked against the rows when there is exactly one)."""
    text = decode_text(data)
    lines = text.splitlines()
    first = None
    count_lines: list[int] = []
    for i, line in enumerate(lines[: _MAX_HEADER_LINES + 1]):
        s = line.strip()
        if not s or is_comment(s):
            continue
        fields = split_fields(s, _delimiter(s))
        if _leading_numbers(fields, 3):
            first = i
            break
        if len(fields) == 1 and fields[0].isdigit():
            count_lines.append(int(fields[0]))
    if first is None:
        raise SkelInputError("no rows with at least 3 numbers (x y z) found", path)
    delim = _delimiter(lines[first].strip())
    rows = _rows(text, first)
    # Multi-scan PTS files repeat the count line before every scan.
    singles = [r for r in rows if r[1].isdigit()]
    if singles:
        single_set = {r[0] for r in singles}
        rows = [r for r in rows if r[0] not in single_set]
        count_lines += [int(r[1]) for r in singles]
    pts = numeric_table(rows, path, delimiter=delim, min_cols=3, use_cols=3, what="x y z")
    if len(count_lines) == 1 and count_lines[0] != len(pts):
        raise SkelInputError(f"point-count line says {count_lines[0]} points, file has {len(pts)} rows", path)
    return RawData(vertices=pts, edges=None, format="XYZ")


def looks_like_obj(text_head: str) -> bool:
    """At least one ``v x y z`` line among the first rows and no row that is only numbers."""
    n_v = 0
    for line in text_head.splitlines()[:200]:
        s = line.strip()
        if not s or is_comment(s):
            continue
        tok = s.split(None, 1)[0]
        if tok == "v":
            n_v += 1
        elif tok in ("vn", "vt", "l", "f", "o", "g", "s", "usemtl", "mtllib", "p"):
            continue
        else:
            return False
    return n_v > 0


def looks_like_polylines(text_head: str) -> bool:
    """Every sampled row is ``n`` then 3n numbers, and some n >= 2 (so it is not x y z + one column)."""
    rows = [ln.split() for ln in text_head.splitlines()[:50] if ln.strip()]
    if len(rows) > 1:
        rows = rows[:-1]  # the head may end mid-line
    if not rows:
        return False
    long = False
    for toks in rows:
        if not toks[0].isdigit() or len(toks) != 1 + 3 * int(toks[0]):
            return False
        long |= int(toks[0]) >= 2
    return long


# ---- OBJ ----------------------------------------------------------------------------------------


def _obj_index(token: str, n_so_far: int, lineno: int, path: Path) -> int:
    """OBJ indices are 1-based; negative ones count back from the last vertex defined so far."""
    head = token.split("/", 1)[0]
    try:
        i = int(head)
    except ValueError:
        raise SkelInputError(f"line {lineno}: {token[:20]!r} is not a vertex index", path) from None
    if i == 0:
        raise SkelInputError(f"line {lineno}: vertex index 0 (OBJ indices start at 1)", path)
    return i - 1 if i > 0 else n_so_far + i


def read_obj(path: Path, data: bytes) -> RawData:
    """``v`` lines (extra values such as w or colours ignored) and ``l`` polylines (consecutive
    indices are edges; ``v/vt`` tokens allowed). Faces are ignored: a mesh OBJ loads as a cloud."""
    text = decode_text(data)
    verts: list[list[str]] = []
    v_lines: list[int] = []
    edges: list[tuple[int, int]] = []
    l_lines: list[tuple[int, int, int]] = []
    has_l = False
    for lineno, line in enumerate(text.splitlines(), 1):
        if not line or line[0] not in "vl \t":
            continue
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "v":
            if len(parts) < 4:
                raise SkelInputError(f"line {lineno}: vertex line has {len(parts) - 1} values, expected 3", path)
            verts.append(parts[1:4])
            v_lines.append(lineno)
        elif parts[0] == "l":
            has_l = True
            idx = [_obj_index(t, len(verts), lineno, path) for t in parts[1:]]
            l_lines.append((lineno, min(idx, default=0), max(idx, default=0)))
            edges.extend(zip(idx[:-1], idx[1:]))
    if verts:
        try:
            vertices = np.array(verts, dtype=np.float64)
        except ValueError:
            vertices = None
        if vertices is None:
            for lineno, toks in zip(v_lines, verts):
                for t in toks:
                    try:
                        float(t)
                    except ValueError:
                        raise SkelInputError(f"line {lineno}: {t[:20]!r} is not a number", path) from None
            raise SkelInputError("vertex coordinates are not numbers", path)
    else:
        vertices = np.empty((0, 3))
    for lineno, lo, hi in l_lines:
        if lo < 0 or hi >= len(verts):
            bad = lo if lo < 0 else hi
            raise SkelInputError(
                f"line {lineno}: vertex index {bad + 1 if bad >= 0 else bad - len(verts)} out of range "
                f"(file has {len(verts)} vertices)",
                path,
            )
    e = np.array(edges, dtype=np.int64).reshape(-1, 2) if has_l else None
    return RawData(vertices=vertices, edges=e, format="OBJ")


# ---- OFF ----------------------------------------------------------------------------------------

_OFF_RE = re.compile(r"^(ST)?(C)?(N)?(4)?(n)?OFF$")


def is_off(first_token: str) -> bool:
    return bool(_OFF_RE.match(first_token))


def read_off(path: Path, data: bytes) -> RawData:
    """Vertices of an (ST)(C)(N)OFF file; faces ignored. Binary OFF is not supported."""
    text = decode_text(data)
    rows = _rows(text)
    if not rows:
        raise SkelInputError("empty OFF file", path)
    head = rows[0][1].split()
    if not is_off(head[0]):
        raise SkelInputError("not an OFF file (first line is not OFF)", path)
    if "4" in head[0] or "n" in head[0]:
        raise SkelInputError(f"{head[0]} (not 3D) is not supported", path)
    if len(head) > 1 and head[1].upper() == "BINARY":
        raise SkelInputError("binary OFF is not supported; save it as ASCII OFF or PLY", path)
    counts, k = (head[1:], 1) if len(head) >= 4 else (rows[1][1].split() if len(rows) > 1 else [], 2)
    if len(counts) < 1 or not counts[0].lstrip("-").isdigit():
        raise SkelInputError("OFF header: missing vertex count", path)
    nv = int(counts[0])
    if nv < 0:
        raise SkelInputError(f"OFF header: negative vertex count {nv}", path)
    body = rows[k : k + nv]
    if len(body) < nv:
        raise SkelInputError(f"truncated: OFF header says {nv} vertices, file has {len(body)}", path)
    if nv == 0:
        return RawData(vertices=np.empty((0, 3)), edges=None, format="OFF")
    ncols = [len(r[1].split()) for r in body]
    if min(ncols) < 3:
        bad = body[int(np.argmin(ncols))][0]
        raise SkelInputError(f"line {bad}: vertex line has fewer than 3 values", path)
    # Vertex rows may carry colours or normals; widths may differ (e.g. C with 3 or 4 channels).
    trimmed = [(ln, " ".join(t.split()[:3])) for ln, t in body]
    pts = numeric_table(trimmed, path, min_cols=3, what="OFF vertex x y z")
    return RawData(vertices=pts, edges=None, format="OFF")


# ---- .cg curve graph ----------------------------------------------------------------------------

_CG_HEAD = re.compile(r"#\s*D\s*:\s*(\d+)\s+NV\s*:\s*(\d+)\s+NE\s*:\s*(\d+)", re.IGNORECASE)


def is_cg(text_head: str) -> bool:
    first = text_head.lstrip().split("\n", 1)[0]
    return bool(re.match(r"#\s*D\s*:\s*\d", first))


def read_cg(path: Path, data: bytes) -> RawData:
    """Starlab curve graph: ``# D:3 NV:n NE:m``, ``v x y z`` lines, ``e i j`` lines with 1-based
    indices (Starlab/cgogn ``curveskel_io_cg``). Some writers use 0-based indices; a file whose
    smallest index is 0 is read as 0-based. Counts must match the header (catches truncation)."""
    text = decode_text(data)
    lines = text.splitlines()
    m = None
    for line in lines[:5]:
        m = _CG_HEAD.match(line.strip())
        if m:
            break
    if m is None:
        raise SkelInputError("not a .cg curve graph (no '# D:3 NV:n NE:m' header)", path)
    dim, nv, ne = (int(g) for g in m.groups())
    if dim != 3:
        raise SkelInputError(f".cg header says D:{dim}; only 3D curve graphs are supported", path)
    v_rows: list[tuple[int, str]] = []
    e_rows: list[tuple[int, str]] = []
    for lineno, line in enumerate(lines, 1):
        s = line.strip()
        if not s or s[0] == "#":
            continue
        tag, _, rest = s.partition(" ")
        if tag == "v":
            v_rows.append((lineno, " ".join(rest.split()[:3])))
        elif tag == "e":
            e_rows.append((lineno, rest.strip()))
        else:
            raise SkelInputError(f"line {lineno}: expected a 'v' or 'e' line, got {s[:20]!r}", path)
    if len(v_rows) != nv or len(e_rows) != ne:
        raise SkelInputError(
            f"header says NV:{nv} NE:{ne}, file has {len(v_rows)} v and {len(e_rows)} e lines "
            "(truncated or malformed)",
            path,
        )
    vertices = numeric_table(v_rows, path, min_cols=3, what="v x y z") if nv else np.empty((0, 3))
    if ne:
        e = numeric_table(e_rows, path, min_cols=2, use_cols=2, what="e i j")
        if np.any(e != np.round(e)):
            raise SkelInputError("edge indices must be whole numbers", path)
        e = e.astype(np.int64)
        base = 0 if e.min() == 0 else 1
        if e.min() < 0 or e.max() - base >= nv:
            bad = e.min() if e.min() < 0 else e.max()
            raise SkelInputError(
                f"edge index {bad} out of range for {nv} vertices ({'0' if base == 0 else '1'}-based)", path
            )
        e = e - base
    else:
        e = np.empty((0, 2), dtype=np.int64)
    return RawData(vertices=vertices, edges=e, format=".cg curve graph", curve_format=True)


# ---- CGAL polylines -----------------------------------------------------------------------------


def read_polylines(path: Path, data: bytes) -> RawData:
    """CGAL ``.polylines.txt``: each line ``n x1 y1 z1 ... xn yn zn`` is a polyline; vertices shared
    between polylines are merged by exact coordinates (that is how CGAL's skeleton output joins)."""
    text = decode_text(data)
    rows = _rows(text)
    if not rows:
        raise SkelInputError("no polylines in file", path)
    chunks = []
    lengths = []
    for lineno, s in rows:
        toks = s.split()
        try:
            n = int(toks[0])
        except ValueError:
            raise SkelInputError(f"line {lineno}: {toks[0][:20]!r} is not a point count", path) from None
        if n < 1 or len(toks) != 1 + 3 * n:
            raise SkelInputError(
                f"line {lineno}: says {n} points but has {len(toks) - 1} numbers (expected {3 * n})", path
            )
        try:
            chunks.append(np.array(toks[1:], dtype=np.float64).reshape(n, 3))
        except ValueError:
            raise SkelInputError(f"line {lineno}: coordinates are not all numbers", path) from None
        lengths.append(n)
    pts = np.concatenate(chunks) + 0.0  # + 0.0 turns -0.0 into 0.0 so both merge
    _, first, inverse = np.unique(pts, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.ravel()
    # Number merged vertices in order of first appearance (stable, readable output).
    rank = np.empty(len(first), dtype=np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(len(first))
    label = rank[inverse]
    vertices = pts[np.sort(first)]
    starts = np.cumsum([0] + lengths[:-1])
    idx = np.arange(len(pts))
    is_last = np.zeros(len(pts), dtype=bool)
    is_last[starts + np.array(lengths) - 1] = True
    a = idx[~is_last]
    edges = np.column_stack([label[a], label[a + 1]]).astype(np.int64)
    return RawData(vertices=vertices, edges=edges, format="CGAL polylines", curve_format=True)


# ---- PyGEL .graph -------------------------------------------------------------------------------


def looks_like_graph(text_head: str) -> bool:
    """PyGEL3D's ``graph.save``: ``n x y z`` node lines, then ``c i j`` connection lines."""
    rows = [ln.split() for ln in text_head.splitlines()[:50] if ln.strip() and not is_comment(ln.strip())]
    if len(rows) > 1:
        rows = rows[:-1]  # the head may end mid-line
    return bool(rows) and rows[0][0] == "n" and all(
        (t[0] == "n" and len(t) == 4) or (t[0] == "c" and len(t) == 3) for t in rows
    )


def read_graph(path: Path, data: bytes) -> RawData:
    """PyGEL ``.graph``: ``n x y z`` adds node k (0-based, in order), ``c i j`` connects nodes i, j."""
    nodes: list[tuple[int, str]] = []
    conns: list[tuple[int, str]] = []
    for lineno, s in _rows(decode_text(data)):
        tag, _, rest = s.partition(" ")
        if tag == "n":
            nodes.append((lineno, rest))
        elif tag == "c":
            conns.append((lineno, rest))
        else:
            raise SkelInputError(f"line {lineno}: expected 'n x y z' or 'c i j', got {s[:30]!r}", path)
    if not nodes:
        raise SkelInputError("PyGEL graph has no 'n x y z' node lines", path)
    v = numeric_table(nodes, path, min_cols=3, what="n x y z")
    if v.shape[1] != 3:
        raise SkelInputError(f"node lines have {v.shape[1]} numbers, expected 3 (n x y z)", path)
    e = np.empty((0, 2))
    if conns:
        e = numeric_table(conns, path, min_cols=2, what="c i j")
        if e.shape[1] != 2:
            raise SkelInputError(f"connection lines have {e.shape[1]} numbers, expected 2 (c i j)", path)
    return RawData(vertices=v, edges=e, format="PyGEL graph", curve_format=True)


# ---- curve writers ------------------------------------------------------------------------------


def _curve_arrays(vertices: np.ndarray, edges: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    v = np.asarray(vertices, dtype=np.float64)
    e = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    if v.ndim != 2 or v.shape[1] != 3:
        raise ValueError(f"vertices must be N x 3, got shape {v.shape}")
    if e.size and (e.min() < 0 or e.max() >= len(v)):
        raise ValueError("edge index out of range")
    return v, e


def write_curve_obj(path, vertices: np.ndarray, edges: np.ndarray, *, inputs=()) -> None:
    """``v x y z`` lines then one ``l i j`` line per edge (1-based), full double precision."""
    from .atomic import atomic_open

    v, e = _curve_arrays(vertices, edges)
    with atomic_open(path, "w", inputs=inputs) as fh:
        fh.write("# written by skelcore: curve skeleton\n")
        np.savetxt(fh, v, fmt="v %.17g %.17g %.17g")
        np.savetxt(fh, e + 1, fmt="l %d %d")


def write_curve_cg(path, vertices: np.ndarray, edges: np.ndarray, *, inputs=()) -> None:
    """Starlab's ``.cg``: ``# D:3 NV:n NE:m``, ``v`` lines, ``e i j`` lines (1-based)."""
    from .atomic import atomic_open

    v, e = _curve_arrays(vertices, edges)
    with atomic_open(path, "w", inputs=inputs) as fh:
        fh.write(f"# D:3 NV:{len(v)} NE:{len(e)}\n")
        np.savetxt(fh, v, fmt="v %.17g %.17g %.17g")
        np.savetxt(fh, e + 1, fmt="e %d %d")
