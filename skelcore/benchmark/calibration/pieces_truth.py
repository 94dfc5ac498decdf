"""The truth of ``disconnected`` on every kind, and of ``missing_cycles`` on the ``broken`` kind
(``skeleton_defects.cut_edges``; docs/diagnostics.md "Disconnected" and "Precision and recall per
warning").

``disconnected`` is true on a broken curve when its pieces exceed the reference's, false on every
other kind with as many pieces as the reference, and left out on a cloud whose reference is in more
pieces than the cloud shows: two of its pieces in one part of the surface, or a piece whose part the
cloud holds no point of. A warning is a hit only when it flags a piece the cut made
(``pieces_located``), not a piece of the reference.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...curve import CurveSkeleton
from ...diagnostics.pieces import curve_pieces
from .skeletons import Made, World

__all__ = ["n_pieces", "reference_split", "disconnected_truth", "cycles_cut"]


def n_pieces(v: np.ndarray, e: np.ndarray) -> tuple[int, np.ndarray]:
    """The curve's pieces (components with an edge; the judge's count) and each vertex's (-1: isolated)."""
    return curve_pieces(CurveSkeleton.from_raw(np.asarray(v, float), np.asarray(e, np.int64).reshape(-1, 2)))


def reference_split(w: World) -> bool:
    """Whether the reference is in more pieces than the cloud shows. A generated shape's exact
    skeleton has one piece per part of the shape and the calibration's scans draw every part, so only
    a reference in several pieces counts (none of the suite's). On a neuron each reference piece lies
    in the mesh part most of its nodes are nearest to; split when two pieces share a part or a piece's
    part holds none of the cloud's surface points (stray points aside)."""
    rv, re, _ = w.ref
    n, piece = n_pieces(rv, re)
    if w.surface_part is None:
        return n > 1
    node_part = w.surface_part(np.asarray(rv, float))
    parts = [int(np.bincount(node_part[piece == p]).argmax()) for p in range(n)]
    shown = set(np.unique(w.surface_part(w.cloud[np.isfinite(w.local_radius)])).tolist())
    return len(set(parts)) < n or not set(parts) <= shown


def _located(w: World, orig: np.ndarray, piece: np.ndarray, flag: np.ndarray | None) -> bool | None:
    """A flagged vertex lies on a piece the cut made: one of several pieces of the curve that share a
    reference piece (``orig``: each vertex's reference twin, -1 none)."""
    if flag is None:
        return None
    rv, re, _ = w.ref
    _, ref_piece = n_pieces(rv, re)
    own = np.where((orig >= 0) & (piece >= 0), ref_piece[np.maximum(orig, 0)], -1)
    split = set()
    for rp in np.unique(own[own >= 0]):
        if len(np.unique(piece[own == rp])) > 1:
            split.add(int(rp))
    on_split = np.isin(own, sorted(split)) & (piece >= 0)
    return bool((flag & on_split).any())


def disconnected_truth(made: Made, w: World, orig: np.ndarray, fired: set[str],
                       flag: np.ndarray | None) -> dict[str, Any]:
    """``truth_disconnected`` (1, 0 or None), the pieces behind it, and ``pieces_located`` (whether a
    fired warning flags a piece the cut made; ``orig``: truth.origin; ``flag``: the disconnected bit
    per vertex)."""
    n_ref = n_pieces(*w.ref[:2])[0]
    n, piece = n_pieces(made.vertices, made.edges)
    split = reference_split(w)
    truth: int | None
    if split:
        truth = None
    elif made.kind == "broken":
        truth = 1 if n > n_ref else None
    else:
        truth = 0 if n == n_ref else None
    located = _located(w, orig, piece, flag) if truth == 1 and "disconnected" in fired else None
    return {"truth_disconnected": truth, "curve_pieces": n, "reference_pieces": n_ref, "reference_split": split,
            "pieces_located": located}


def cycles_cut(made: Made, w: World) -> int:
    """1 when ``made`` has fewer independent cycles (edges - vertices + pieces) than the reference
    (the truth of ``missing_cycles`` on a broken curve: a cut through a ring opens it), else 0."""
    def rank(v: np.ndarray, e: np.ndarray) -> int:
        n, piece = n_pieces(v, e)
        return len(e) - int((piece >= 0).sum()) + n

    return int(rank(made.vertices, made.edges) < rank(*w.ref[:2]))
