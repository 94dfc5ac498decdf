"""TreeQSM cylinder models (``.mat``) as curve skeletons with radii.

TreeQSM (Raumonen et al. 2013) saves a QSM struct whose ``cylinder`` field holds one row per cylinder:
``start`` (x y z), ``axis`` (unit direction), ``length``, ``radius`` and ``parent`` (1-based, 0 for
none); TreeQSM 2.x saved the same as ``Sta``, ``Axe``, ``Len``, ``Rad``, ``CPar``. Each cylinder is an
edge from its start to its end (start + length * axis). A cylinder that continues its parent starts at
the parent's end and shares that vertex; a branch starts on the side of its parent: the parent's edge
is split at the branch start's projection on its axis, joined to the branch start by a short edge.
Vertex radii: a cylinder's radius at its start and end, the parent's at a split point.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from ..errors import SkelInputError
from ._common import RawData

__all__ = ["is_mat", "read_treeqsm", "cylinders_to_curve"]

_FIELDS = {
    "start": ("start", "sta"),
    "axis": ("axis", "axe"),
    "length": ("length", "len"),
    "radius": ("radius", "rad"),
    "parent": ("parent", "cpar"),
}


def is_mat(head: bytes) -> bool:
    return head.startswith(b"MATLAB")


def _fields_of(obj: object) -> dict[str, object]:
    """Field name (lower case) -> value of a loaded struct (scipy's mat_struct) or a dict of variables."""
    if isinstance(obj, dict):
        return {k.lower(): v for k, v in obj.items() if not k.startswith("__")}
    names = getattr(obj, "_fieldnames", None)
    if names is not None:
        return {n.lower(): getattr(obj, n) for n in names}
    return {}


def _find_model(obj: object, depth: int = 0) -> dict[str, object] | None:
    """The first struct (depth-first, at most 4 levels) holding start, axis, length and radius."""
    if isinstance(obj, np.ndarray) and obj.dtype == object:
        for item in obj.ravel()[:16]:
            found = _find_model(item, depth)
            if found is not None:
                return found
        return None
    fields = _fields_of(obj)
    if not fields:
        return None
    picked = {role: next((fields[a] for a in names if a in fields), None) for role, names in _FIELDS.items()}
    if all(picked[k] is not None for k in ("start", "axis", "length", "radius")):
        return picked
    if depth >= 4:
        return None
    for key in ("cylinder", "qsm", *fields):
        if key in fields:
            found = _find_model(fields[key], depth + 1)
            if found is not None:
                return found
    return None


def read_treeqsm(path: Path, data: bytes) -> RawData:
    """A TreeQSM ``.mat`` (MATLAB v4-v7; v7.3 HDF5 files are refused in one line) as a curve with radii."""
    from scipy.io import loadmat

    if b"MATLAB 7.3" in data[:128]:
        raise SkelInputError("MATLAB v7.3 (HDF5) .mat files are not read: save the QSM with save(..., '-v7')", path)
    try:
        variables = loadmat(io.BytesIO(data), squeeze_me=True, struct_as_record=False)
    except Exception as exc:  # scipy's messages name the problem; keep one line
        raise SkelInputError(f"cannot read .mat file: {' '.join(str(exc).split())[:120]}", path) from None
    model = _find_model(variables)
    if model is None:
        have = ", ".join(k for k in variables if not k.startswith("__")) or "none"
        raise SkelInputError(
            f".mat file holds no TreeQSM cylinder model (a struct with start, axis, length, radius; variables: {have})",
            path,
        )
    try:
        start = np.asarray(model["start"], dtype=np.float64).reshape(-1, 3)
        axis = np.asarray(model["axis"], dtype=np.float64).reshape(-1, 3)
        length = np.asarray(model["length"], dtype=np.float64).ravel()
        radius = np.asarray(model["radius"], dtype=np.float64).ravel()
        parent = None if model["parent"] is None else np.asarray(model["parent"], dtype=np.float64).ravel()
    except (TypeError, ValueError):
        raise SkelInputError("TreeQSM cylinder fields are not numeric arrays", path) from None
    vertices, edges, vradius = cylinders_to_curve(start, axis, length, radius, parent, path=path)
    return RawData(vertices=vertices, edges=edges, format="TreeQSM", curve_format=True, radius=vradius)


def cylinders_to_curve(
    start: np.ndarray, axis: np.ndarray, length: np.ndarray, radius: np.ndarray,
    parent: np.ndarray | None = None, *, path: object | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(vertices, edges, vertex radii) of n cylinders; ``parent`` 1-based with 0 for none (TreeQSM),
    or None to join cylinders whose start is at another's end."""
    n = len(start)
    if not (len(axis) == len(length) == len(radius) == n) or (parent is not None and len(parent) != n):
        raise SkelInputError("TreeQSM cylinder fields have different lengths", path)
    if n == 0:
        raise SkelInputError("TreeQSM model has no cylinders", path)
    if not all(np.all(np.isfinite(a)) for a in (start, axis, length, radius)):
        raise SkelInputError("TreeQSM cylinder fields contain NaN or inf", path)
    norms = np.linalg.norm(axis, axis=1, keepdims=True)
    axis = np.divide(axis, norms, out=np.zeros_like(axis), where=norms > 0)
    end = start + axis * length[:, None]
    tol = 1e-6 * max(float(np.ptp(np.vstack([start, end]), axis=0).max()), 1e-12)
    # vertex ids: end of cylinder i -> i, start of cylinder i -> n + i, split points -> 2n + k
    start_node = np.arange(n) + n
    if parent is None:
        from scipy.spatial import cKDTree

        d, j = cKDTree(end).query(start, k=1)
        par = np.where((d <= tol) & (j != np.arange(n)), j, -1)
    else:
        if np.any(parent != np.round(parent)) or np.any(parent < 0) or np.any(parent > n):
            raise SkelInputError(f"TreeQSM parent indices must be whole numbers in 0..{n}", path)
        par = parent.astype(np.int64) - 1
    has = par >= 0
    p = np.where(has, par, 0)
    joined = has & (np.linalg.norm(start - end[p], axis=1) <= tol)
    start_node[joined] = p[joined]
    # branches: where along the parent's axis they leave it
    branch = np.flatnonzero(has & ~joined)
    bp = p[branch]
    t = np.clip(np.einsum("ij,ij->i", start[branch] - start[bp], axis[bp]), 0.0, length[bp])
    at_end = t >= length[bp] - tol
    at_start = t <= tol
    middle = ~(at_end | at_start)
    n_split = int(middle.sum())
    split_ids = 2 * n + np.arange(n_split)
    split_xyz = start[bp[middle]] + axis[bp[middle]] * t[middle, None]
    attach = np.empty(len(branch), np.int64)
    attach[at_end] = bp[at_end]
    attach[at_start & ~at_end] = start_node[bp[at_start & ~at_end]]
    attach[middle] = split_ids
    join_edges = np.column_stack([start_node[branch], attach])
    # each cylinder's own edge, through its split points in order of t
    seq_cyl = np.concatenate([np.arange(n), np.arange(n), bp[middle]])
    seq_t = np.concatenate([np.full(n, -1.0), np.full(n, np.inf), t[middle]])
    seq_node = np.concatenate([start_node, np.arange(n), split_ids])
    order = np.lexsort((seq_t, seq_cyl))
    same = seq_cyl[order][1:] == seq_cyl[order][:-1]
    chain = np.column_stack([seq_node[order][:-1][same], seq_node[order][1:][same]])
    edges = np.vstack([chain, join_edges])
    vertices = np.vstack([end, start, split_xyz])
    vradius = np.concatenate([radius, radius, radius[bp[middle]]])
    used = np.zeros(len(vertices), bool)
    used[edges.ravel()] = True
    new_index = np.cumsum(used) - 1
    return vertices[used], new_index[edges], vradius[used]
