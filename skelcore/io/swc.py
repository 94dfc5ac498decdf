"""SWC (``id type x y z radius parent`` rows): the reader, the writer, and the parent-table -> edges step
shared with a pandas DataFrame of SWC rows and a navis TreeNeuron (:mod:`skelcore.interop`).

SWC holds a forest: every node has at most one parent, so a curve with a cycle cannot be written
(:func:`write_swc` refuses it; ``skelcore convert`` says so). Radii <= 0 are read as unknown.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Iterable

import numpy as np

from ..errors import SkelInputError
from ._common import RawData, decode_text, numeric_table
from .atomic import atomic_open
from .text import _rows

__all__ = ["read_swc", "write_swc", "parent_edges", "forest_parents"]


def parent_edges(ids: np.ndarray, parents: np.ndarray, path: object | None = None) -> np.ndarray:
    """Edges (row, parent's row) of an SWC table: ids unique whole numbers in any order, a negative
    parent marks a root, a parent missing from the table is a one-line SkelInputError."""
    ids = np.asarray(ids, dtype=float)
    parents = np.asarray(parents, dtype=float)
    if not (np.all(np.isfinite(ids)) and np.all(np.isfinite(parents))) or np.any(ids != np.round(ids)) \
            or np.any(parents != np.round(parents)):
        raise SkelInputError("SWC ids and parent ids must be whole numbers", path)
    ids = ids.astype(np.int64)
    parents = parents.astype(np.int64)
    order = np.argsort(ids, kind="stable")
    sorted_ids = ids[order]
    dup = np.flatnonzero(sorted_ids[1:] == sorted_ids[:-1])
    if dup.size:
        raise SkelInputError(f"SWC id {int(sorted_ids[dup[0]])} appears more than once", path)
    child = np.flatnonzero(parents >= 0)
    if len(ids) == 0:
        return np.empty((0, 2), np.int64)
    pos = np.minimum(np.searchsorted(sorted_ids, parents[child]), len(sorted_ids) - 1)
    found = sorted_ids[pos] == parents[child]
    if not found.all():
        k = child[~found][0]
        raise SkelInputError(f"SWC node {int(ids[k])} has parent {int(parents[k])}, which is not in the file", path)
    return np.column_stack([child, order[pos]]).astype(np.int64)


def read_swc(path: Path, data: bytes) -> RawData:
    """SWC rows ``id type x y z radius parent``; parent -1 (any negative) marks a root; ids may be
    non-contiguous and appear in any order. Each non-root row gives the edge (row, parent's row)."""
    table = numeric_table(_rows(decode_text(data)), path, min_cols=7, use_cols=7, what="id type x y z radius parent")
    edges = parent_edges(table[:, 0], table[:, 6], path)
    radius = table[:, 5].copy()
    radius = None if np.all(~(radius > 0)) else np.where(radius > 0, radius, np.nan)
    return RawData(vertices=table[:, 2:5].copy(), edges=edges, format="SWC", curve_format=True, radius=radius)


def forest_parents(n: int, edges: np.ndarray, *, spanning: bool = False) -> np.ndarray:
    """Parent row of every vertex (-1 for the root of each component) of an undirected forest, by a
    breadth-first search from each component's lowest-numbered vertex; ValueError on a cycle, unless
    ``spanning`` (then the breadth-first spanning forest: each cycle loses one edge)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import breadth_first_order, connected_components

    e = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    adj = coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n)).tocsr()
    n_comp, labels = connected_components(adj, directed=False)
    if len(e) != n - n_comp and not spanning:
        raise ValueError(f"the curve has {len(e) - n + n_comp} independent cycle(s); SWC holds only trees")
    parents = np.full(n, -1, np.int64)
    roots = np.unique(labels, return_index=True)[1]
    # one BFS over a super-root joined to every component's root gives every parent in one call
    sym = adj + adj.T
    sym = sym.tocoo()
    rows = np.concatenate([sym.row, np.full(len(roots), n)])
    cols = np.concatenate([sym.col, roots])
    big = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n + 1, n + 1)).tocsr()
    _order, pred = breadth_first_order(big, n, directed=True, return_predecessors=True)
    parents[:] = pred[:n]
    parents[parents == n] = -1
    return parents


def write_swc(
    path: str | os.PathLike, vertices: np.ndarray, edges: np.ndarray, radius: np.ndarray | None = None, *,
    inputs: Iterable[str | os.PathLike] = (), spanning: bool = False,
) -> None:
    """A forest curve as SWC: vertex i is node i + 1 (vertex order kept), type 0, its radius (0 when
    unknown), its parent from a breadth-first search of its component. ValueError on a cycle unless
    ``spanning`` (then one edge of each cycle is dropped)."""
    v = np.asarray(vertices, dtype=np.float64)
    parents = forest_parents(len(v), edges, spanning=spanning)
    r = np.zeros(len(v)) if radius is None else np.nan_to_num(np.asarray(radius, float), nan=0.0)
    ids = np.arange(1, len(v) + 1)
    table = np.column_stack([ids, np.zeros(len(v)), v, r, np.where(parents >= 0, parents + 1, -1)])
    with atomic_open(path, "w", inputs=inputs) as fh:
        fh.write("# written by skelcore\n# id type x y z radius parent\n")
        np.savetxt(fh, table, fmt=["%d", "%d", "%.17g", "%.17g", "%.17g", "%.17g", "%d"])
