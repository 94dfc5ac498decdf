"""Terminal branches that end at a cut in the curve, not in the shape: not spurs (docs/diagnostics.md
"Spurious branches", rule 6, and "Cut ends of a broken curve").

A curve broken into pieces (an edge lost: docs/diagnostics.md "Disconnected") gives each side of the
cut a new free end. The branch from a junction to such an end can fail both spur measures: the piece
across the gap explains its territory, and a cut near the junction leaves it inside the junction's
ball. Its tip differs from a spur's by what lies ahead of it: the curve goes on. A tip is a **cut
end** when the nearest vertex q of another piece of the curve lies within ``spur_cut_gap`` local
radii of it (the larger of the two ends' distances to the cloud), ahead of it (the gap's direction
within ``spur_cut_angle`` degrees of the branch's own at its tip, read over one local radius of it),
the tip is in turn its piece's nearest vertex to q (the two ends of a cut face each other; a twig
beside another piece's neurite has its own piece's nodes nearer to it), and the cloud fills the gap:
every point of the segment from the tip to q, every ``diag_step`` local radii, lies within
(1 + ``spur_slack``) times the radius interpolated between its ends of the cloud, the same grown
balls the explanation measure reads. A spur's tip lies where the cloud ends or in the
air; no piece continues it through the shape. A curve in one piece costs one count of its pieces.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..curve import CurveSkeleton
from ..params import Params
from .branches import Branches
from .pieces import curve_pieces

__all__ = ["CutEnds", "cut_ends"]

_K = 16  # nearest vertices searched first for another piece's (a tip with none among them: its own search)


class CutEnds:
    """Per terminal branch (the order of ``terminal``): ``cut`` whether its tip is a cut end, ``other``
    the nearest vertex of another piece (-1 none), ``gap`` its distance in local radii, ``cos`` the
    cosine between the branch's direction at its tip and the gap's, ``fill`` the largest ratio of the
    cloud's distance along the gap to the interpolated radius (NaN where not measured)."""

    def __init__(self, n: int) -> None:
        self.cut = np.zeros(n, bool)
        self.other = np.full(n, -1, np.int64)
        self.gap = np.full(n, np.nan)
        self.cos = np.full(n, np.nan)
        self.fill = np.full(n, np.nan)


def _tip_direction(v: np.ndarray, path: np.ndarray, tip_first: bool, length: float) -> np.ndarray:
    """The unit direction from the path's vertex ``length`` back from its tip (or its far end) to the tip."""
    p = path if tip_first else path[::-1]
    d = np.linalg.norm(v[p] - v[p[0]], axis=1)
    far = np.flatnonzero((d >= length) & (d > 0))
    back = p[far[0]] if len(far) else p[-1]
    u = v[p[0]] - v[back]
    n = float(np.linalg.norm(u))
    return u / n if n > 0 else u


def _nearest_of(v: np.ndarray, piece: np.ndarray, at: np.ndarray, target: np.ndarray, same: bool) -> np.ndarray:
    """Per vertex ``at[i]``, the nearest vertex whose piece is ``target[i]`` (``same``) or is not (-1:
    none such)."""
    used = np.flatnonzero(piece >= 0)
    out = np.full(len(at), -1, np.int64)
    if not len(at) or not len(used):
        return out
    tree = cKDTree(v[used])
    k = min(_K, len(used))
    _, j = tree.query(v[at], k=k)
    j = used[np.asarray(j).reshape(len(at), k)]
    hit = (piece[j] == target[:, None]) == same
    has = hit.any(axis=1)
    out[has] = j[has, np.argmax(hit[has], axis=1)]
    for i in np.flatnonzero(~has):  # none among the k nearest: a search of its own
        rest = used[(piece[used] == target[i]) == same]
        if len(rest):
            out[i] = rest[int(cKDTree(v[rest]).query(v[at[i]])[1])]
    return out


def cut_ends(curve: CurveSkeleton, branches: Branches, terminal: np.ndarray, cloud_tree: cKDTree,
             params: Params = Params()) -> CutEnds:
    """Which terminal branches of ``curve`` end at a cut (module docstring; normalized inputs,
    docs/metrics.md 0; ``cloud_tree``: the diagnostics' KD-tree of the cloud, r(x) = distance to it)."""
    terminal = np.asarray(terminal, np.int64)
    res = CutEnds(len(terminal))
    points = sum(k == "point" for k in branches.kind)
    if int(branches.n_components) - points <= 1 or not len(terminal) or cloud_tree.n == 0:
        return res
    _, piece = curve_pieces(curve)
    v = np.asarray(curve.vertices, float)
    deg = curve.degrees()
    paths = [np.asarray(branches.paths[b], np.int64) for b in terminal]
    tip_first = np.array([deg[p[0]] == 1 for p in paths])
    tips = np.array([p[0] if f else p[-1] for p, f in zip(paths, tip_first)], np.int64)
    other = _nearest_of(v, piece, tips, piece[tips], same=False)
    ok = np.flatnonzero(other >= 0)
    if not len(ok):
        return res
    r_ends = cloud_tree.query(np.vstack([v[tips[ok]], v[other[ok]]]))[0]
    r_tip, r_oth = r_ends[:len(ok)], r_ends[len(ok):]
    scale = np.maximum(r_tip, r_oth)
    dist = np.linalg.norm(v[other[ok]] - v[tips[ok]], axis=1)
    res.other[ok] = other[ok]
    with np.errstate(divide="ignore", invalid="ignore"):
        res.gap[ok] = np.where(scale > 0, dist / scale, np.where(dist > 0, np.inf, 0.0))
    for t, i in enumerate(ok):
        u = _tip_direction(v, paths[i], bool(tip_first[i]), float(r_tip[t]))
        g = v[other[i]] - v[tips[i]]
        res.cos[i] = float(u @ g / dist[t]) if dist[t] > 0 else 1.0
    near = ok[(res.gap[ok] <= params.spur_cut_gap) & (res.cos[ok] >= np.cos(np.radians(params.spur_cut_angle)))]
    # the two ends of a cut face each other: the tip is the nearest vertex of its piece to q too
    near = near[_nearest_of(v, piece, other[near], piece[tips[near]], same=True) == tips[near]]
    if not len(near):
        return res
    # the gap's points every diag_step radii against the balls interpolated between its ends
    at = np.searchsorted(ok, near)
    steps = np.maximum(np.ceil(dist[at] / np.maximum(params.diag_step * np.minimum(r_tip[at], r_oth[at]), 1e-12)), 1)
    steps = np.minimum(steps, 256).astype(np.int64)
    s = np.concatenate([np.linspace(0.0, 1.0, int(n) + 1) for n in steps])
    row = np.repeat(np.arange(len(near)), steps + 1)
    a, b = v[tips[near]][row], v[other[near]][row]
    x = a + s[:, None] * (b - a)
    d = cloud_tree.query(x)[0]
    ball = (1.0 + params.spur_slack) * ((1.0 - s) * r_tip[at][row] + s * r_oth[at][row])
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(ball > 0, d / ball, np.where(d > 0, np.inf, 0.0))
    worst = np.zeros(len(near))
    np.maximum.at(worst, row, ratio)
    res.fill[near] = worst
    res.cut[near] = worst <= 1.0
    return res
