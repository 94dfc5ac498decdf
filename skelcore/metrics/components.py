"""Connected components of an undirected graph given by its edges, labelled as
``scipy.sparse.csgraph.connected_components(graph, directed=False)`` labels them (components numbered in
the order of their smallest node) by the compiled union-find ``_components.c``: no compressed rows, no
transpose, no depth-first walk (the missing parts' regions, docs/performance.md 6.10)."""

from __future__ import annotations

import numpy as np

from . import _components

__all__ = ["undirected_components"]


def undirected_components(n: int, heads: np.ndarray, tails: np.ndarray) -> tuple[int, np.ndarray]:
    """(number of components, int32 label per node) of the graph on nodes 0 .. n - 1 with an edge
    between ``heads[e]`` and ``tails[e]`` for every e (either direction, repeats and loops allowed):
    scipy's ``connected_components`` of any sparse matrix with these entries, ``directed=False``."""
    heads = np.ascontiguousarray(heads, dtype=np.int64).ravel()
    tails = np.ascontiguousarray(tails, dtype=np.int64).ravel()
    if heads.shape != tails.shape:
        raise ValueError(f"heads {heads.shape} and tails {tails.shape} must have the same length")
    labels = np.empty(int(n), np.int32)
    count = _components.components(int(n), heads, tails, labels)
    return int(count), labels
