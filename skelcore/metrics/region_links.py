"""The missing parts' region graph and border from the cloud's kept neighbour answers, in one compiled pass
over the unexplained points (``_region_links.c``; the rules: :func:`skelcore.diagnostics.missing_parts._regions`,
docs/diagnostics.md "Missing parts"; numbers: docs/performance.md 6.10, "The non-ray stages of a pruned
branch, compiled")."""

from __future__ import annotations

import numpy as np

from . import _region_links

__all__ = ["region_links"]


def region_links(dist: np.ndarray, cloud: np.ndarray, sel: np.ndarray, at: np.ndarray, covered: np.ndarray,
                 k: int, kk: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """What the first answers of each unexplained point settle. ``dist``, ``cloud``: a table of the K nearest
    cloud points within the link (distances; cloud rows, n = ``len(covered)`` where fewer), unexplained
    point i's answers in row ``sel[i]``; ``at``: each cloud row's unexplained row, -1 when explained (n + 1
    entries, the last -1); ``covered``: the explained cloud points. Returns (heads, tails): the links of the
    points whose first ``k`` answers are the only k nearest, all found unexplained and none but the first at
    distance 0 (the point to its k - 1 nearest others, as ``cKDTree(unexplained).query(k=k)`` finds them);
    ``unsettled``: the other points (no links written); ``border``: an explained point among the first
    ``kk`` answers found; ``unsure``: those ``kk`` are not the only kk nearest."""
    dist = np.ascontiguousarray(dist, dtype=np.float64)
    width = dist.shape[1]
    cloud = np.ascontiguousarray(cloud, dtype=np.int32)
    if cloud.shape != dist.shape:
        raise ValueError(f"the distances {dist.shape} and cloud rows {cloud.shape} must have one shape")
    sel = np.ascontiguousarray(sel, dtype=np.int64)
    m = len(sel)
    heads, tails = np.empty(m * (k - 1), np.int64), np.empty(m * (k - 1), np.int64)
    unsettled, border, unsure = np.empty(m, bool), np.empty(m, bool), np.empty(m, bool)
    count = _region_links.links(dist, cloud, width, sel, np.ascontiguousarray(at, dtype=np.int32),
                                np.ascontiguousarray(covered, dtype=bool), int(k), int(kk), heads, tails,
                                unsettled, border, unsure)
    return heads[:count], tails[:count], unsettled, border, unsure
