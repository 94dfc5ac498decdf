"""NumPy (.npy, .npz) and JSON point sets and ``{vertices, edges[, radius]}`` curve skeletons; the JSON
curve writer."""

from __future__ import annotations

import io
import json
import zipfile
from pathlib import Path

import numpy as np

from ..errors import SkelInputError
from ._common import RawData, as_edges, as_vertices, decode_text

_POINT_KEYS = ("points", "cloud", "vertices", "verts", "xyz", "pts", "positions", "nodes")
_EDGE_KEYS = ("edges", "lines", "links")


def _pick(keys, wanted: tuple[str, ...]) -> str | None:
    lower = {k.lower(): k for k in keys}
    for w in wanted:
        if w in lower:
            return lower[w]
    return None


def _load_npy_bytes(data: bytes, path: Path, what: str = "NPY") -> np.ndarray:
    """``np.load`` after checking the header's shape against the bytes present, so a corrupt header
    cannot make numpy allocate a huge array before noticing the file is short."""
    f = io.BytesIO(data)
    version = np.lib.format.read_magic(f)
    if version == (1, 0):
        shape, _, dtype = np.lib.format.read_array_header_1_0(f)
    else:
        shape, _, dtype = np.lib.format.read_array_header_2_0(f)
    if dtype.hasobject:
        raise SkelInputError(f"{what} holds Python objects, not numbers", path)
    need = int(np.prod(shape, dtype=np.float64)) * dtype.itemsize
    if need > len(data) - f.tell():
        raise SkelInputError(f"truncated: {what} header promises {need} bytes, file has {len(data) - f.tell()}", path)
    return np.load(io.BytesIO(data), allow_pickle=False)


def read_npy(path: Path, data: bytes) -> RawData:
    """An (N, 3) array (N x k with k > 3: the first three columns), or a record array with x, y, z."""
    return RawData(vertices=as_vertices(_load_npy_bytes(data, path), path), edges=None, format="NPY")


def read_npz(path: Path, data: bytes) -> RawData:
    """A point array under points/cloud/vertices/xyz/... (or the only array); with an ``edges``
    array the file is a curve skeleton ``{vertices, edges}`` (0-based indices)."""
    with zipfile.ZipFile(io.BytesIO(data)) as zf:
        members = {n[:-4] if n.endswith(".npy") else n: n for n in zf.namelist()}
        keys = list(members)
        if not keys:
            raise SkelInputError("NPZ archive holds no arrays", path)
        ekey = _pick(keys, _EDGE_KEYS)
        vkey = _pick([k for k in keys if k != ekey], _POINT_KEYS)
        if vkey is None:
            rest = [k for k in keys if k != ekey]
            if len(rest) != 1:
                raise SkelInputError(
                    f"NPZ: cannot tell which array holds the points (arrays: {', '.join(keys)}); "
                    "name it 'points' or 'vertices'",
                    path,
                )
            vkey = rest[0]
        vertices = as_vertices(_load_npy_bytes(zf.read(members[vkey]), path, f"NPZ array {vkey!r}"), path)
        edges = None
        if ekey is not None:
            edges = as_edges(_load_npy_bytes(zf.read(members[ekey]), path, f"NPZ array {ekey!r}"), path)
    return RawData(vertices=vertices, edges=edges, format="NPZ")


def read_json(path: Path, data: bytes) -> RawData:
    """``{"vertices": [[x, y, z], ...], "edges": [[i, j], ...]}`` (0-based), ``{"points": ...}``, or
    a bare list of [x, y, z] rows."""
    doc = json.loads(decode_text(data))
    if isinstance(doc, list):
        return RawData(vertices=_json_vertices(doc, path), edges=None, format="JSON")
    if not isinstance(doc, dict):
        raise SkelInputError("JSON must be an object with 'vertices' (and 'edges') or a list of points", path)
    vkey = _pick(doc.keys(), _POINT_KEYS)
    if vkey is None:
        raise SkelInputError(
            f"JSON object has no 'vertices' or 'points' key (keys: {', '.join(list(doc)[:8])})", path
        )
    ekey = _pick(doc.keys(), _EDGE_KEYS)
    vertices = _json_vertices(doc[vkey], path)
    edges = None
    if ekey is not None:
        e = doc[ekey]
        if not isinstance(e, list) or any(not isinstance(r, list) for r in e):
            raise SkelInputError(f"JSON '{ekey}' must be a list of [i, j] pairs", path)
        if any(len(r) != 2 or not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in r) for r in e):
            raise SkelInputError(f"JSON '{ekey}' must be a list of [i, j] number pairs", path)
        edges = as_edges(np.array(e, dtype=np.float64).reshape(-1, 2), path)
    radius = None
    rkey = _pick(doc.keys(), ("radius", "radii"))
    if rkey is not None and edges is not None:
        r = doc[rkey]
        if not isinstance(r, list) or len(r) != len(vertices) or \
                not all(x is None or (isinstance(x, (int, float)) and not isinstance(x, bool)) for x in r):
            raise SkelInputError(f"JSON '{rkey}' must be a list of one number (or null) per vertex", path)
        radius = np.array([np.nan if x is None else x for x in r], dtype=np.float64)
    return RawData(vertices=vertices, edges=edges, format="JSON", radius=radius)


def _json_vertices(rows: object, path: Path) -> np.ndarray:
    if not isinstance(rows, list):
        raise SkelInputError("JSON vertices must be a list of [x, y, z] rows", path)
    if not rows:
        return np.empty((0, 3))
    ok = all(
        isinstance(r, list) and len(r) >= 3
        and all(isinstance(x, (int, float)) and not isinstance(x, bool) or x is None for x in r[:3])
        for r in rows
    )  # fmt: skip
    if not ok:
        raise SkelInputError("JSON vertices must be a list of [x, y, z] number rows", path)
    # null (how NaN is usually written to JSON) becomes NaN.
    return np.array([[np.nan if x is None else x for x in r[:3]] for r in rows], dtype=np.float64)


def write_curve_json(path, vertices: np.ndarray, edges: np.ndarray, radius: np.ndarray | None = None, *,
                     inputs=()) -> None:
    """``{"vertices": [[x, y, z], ...], "edges": [[i, j], ...]}`` (0-based), plus ``"radius"`` when
    known (NaN, an unknown radius, written as null); floats round-trip exactly."""
    from .atomic import atomic_open

    doc = {"vertices": np.asarray(vertices, dtype=np.float64).tolist(),
           "edges": np.asarray(edges, dtype=np.int64).reshape(-1, 2).tolist()}
    if radius is not None:
        doc["radius"] = [None if not np.isfinite(r) else r for r in np.asarray(radius, dtype=np.float64).tolist()]
    with atomic_open(path, "w", inputs=inputs) as fh:
        json.dump(doc, fh)
        fh.write("\n")
