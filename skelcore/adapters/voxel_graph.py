"""Skeleton voxels as a graph: one vertex per voxel, an edge between 26-neighbours.

A one-voxel-thin skeleton still holds triangles in its 26-neighbourhood (a diagonal step beside the
two face steps it short-cuts), which would read as tiny cycles. A diagonal edge is dropped when
another skeleton voxel lies in the unit square (face diagonal) or unit cube (body diagonal) it
spans: that voxel joins its two ends by strictly shorter edges, so by induction on the length no
connection is lost and no cycle of the skeleton is cut. Everything is vectorized over the voxels.
"""

from __future__ import annotations

import itertools

import numpy as np

__all__ = ["voxel_edges"]

# the 13 offsets of the 26-neighbourhood with a positive first non-zero component (each pair once)
_OFFSETS = np.array([d for d in itertools.product((-1, 0, 1), repeat=3)
                     if any(d) and d[np.flatnonzero(d)[0]] > 0], dtype=np.int64)


def _keys(vox: np.ndarray, lo: np.ndarray, dims: np.ndarray) -> np.ndarray:
    v = vox - lo
    return (v[:, 0] * dims[1] + v[:, 1]) * dims[2] + v[:, 2]


def voxel_edges(voxels: np.ndarray) -> np.ndarray:
    """Edges (E x 2, rows into ``voxels``) of the 26-neighbourhood graph of integer ``voxels``
    (M x 3, unique), the short-cut diagonals left out."""
    vox = np.asarray(voxels, dtype=np.int64)
    if len(vox) < 2:
        return np.empty((0, 2), dtype=np.int64)
    lo = vox.min(axis=0) - 1
    dims = vox.max(axis=0) - lo + 2
    keys = _keys(vox, lo, dims)
    order = np.argsort(keys)
    sorted_keys = keys[order]

    def lookup(points: np.ndarray) -> np.ndarray:
        """Row of each point in ``voxels``, -1 where it is not a skeleton voxel."""
        k = _keys(points, lo, dims)
        i = np.minimum(np.searchsorted(sorted_keys, k), len(sorted_keys) - 1)
        return np.where(sorted_keys[i] == k, order[i], -1)

    out = []
    for d in _OFFSETS:
        nb = lookup(vox + d)
        a = np.flatnonzero(nb >= 0)
        if len(a) == 0:
            continue
        keep = np.ones(len(a), dtype=bool)
        if np.abs(d).sum() > 1:  # a diagonal: is another voxel of its square / cube a skeleton voxel?
            axes = np.flatnonzero(d)
            for mask in itertools.product((0, 1), repeat=len(axes)):
                if 0 < sum(mask) < len(axes):
                    step = np.zeros(3, dtype=np.int64)
                    step[axes] = d[axes] * np.array(mask)
                    keep &= lookup(vox[a] + step) < 0
        out.append(np.column_stack([a[keep], nb[a[keep]]]))
    edges = np.concatenate(out) if out else np.empty((0, 2), dtype=np.int64)
    return np.sort(edges, axis=1)
