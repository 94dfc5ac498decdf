"""The truth per warning code for one evaluated skeleton: 1 (the defect or condition is there), 0
(it is not) or None (left out of both rates), from what the suite knows (docs/diagnostics.md
"Precision and recall per warning").

Injected kinds decide the skeleton codes (spurs: ``spurious_branches``, a chord: ``spurious_cycles``,
a broken cycle: ``missing_cycles``, collapse 0.9: ``collapse``, another frame: ``frame``); geometry
decides ``outside`` (how far the skeleton leaves the shape, in the nearest reference radius) and
``incomplete`` (the reference's length farther than two radii from the skeleton); the scan decides
the cloud codes. On a neuron, about half the traced nodes lie outside the decimated mesh the cloud is
drawn from: an ``outside`` flag on a branch mostly outside it is neither a hit nor a false alarm, and
``spurious_branches`` is decided twig by twig (:func:`twig_kinds`: a twig wholly beyond the mesh is
spurious relative to the cloud, one within a radius of it is not); a defect under the size the cloud
resolves (``outside_seen``, ``uncovered_area``) is left out, not a miss.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ...params import Params
from .pieces_truth import cycles_cut, disconnected_truth
from ..skeleton_defects import vertex_tangents
from .skeletons import Made, World
from .uncovered import MISS_AREA, _radius_at, _samples, uncovered_area, uncovered_radii

__all__ = ["OUT_YES", "OUT_NO", "MISS_YES", "MISS_NO", "MISS_AREA", "origin", "outside_depth", "outside_seen",
           "uncovered_radii", "uncovered_area", "thin_share", "unbounded_share", "sparse_drop", "row_truth", "TWIG_OUT",
           "twig_kinds", "along_surface_truth", "SURF_YES", "SURF_NO"]

#: ``outside`` is true from this depth out of the shape (local radii; the shortcut generator's promise)
OUT_YES = 0.5
#: ... and false below this depth (in between: left out)
OUT_NO = 0.1
#: ``incomplete`` is true when more than this length of the reference (local radii) lies farther than
#: two radii from the skeleton, false under MISS_NO (docs/diagnostics.md "Missing parts", Calibration)
MISS_YES, MISS_NO = 2.0, 1.0
#: a neuron's traced twig (a terminal branch's own nodes) is shown by the cloud when every node lies inside
#: the mesh or at most this many traced radii out of it, beyond the cloud when every node lies farther
#: (docs/benchmark.md "The real suite", docs/diagnostics.md "Precision and recall per warning")
TWIG_OUT = 1.0
#: kinds that move the whole skeleton: every branch and cycle verdict on them is left out
GLOBAL_KINDS = ("collapse", "frame", "nodes_only")
#: ``along_surface`` is true when the offset skeleton's vertices lie at least this many local radii off
#: the axis across it (the median; the part along the axis moves nothing off it), false at most SURF_NO
SURF_YES = 0.6
SURF_NO = 0.3


def origin(made: Made, ref_v: np.ndarray) -> np.ndarray:
    """Per vertex of ``made``, the reference vertex at the same place, or -1 (injected or moved)."""
    d, i = cKDTree(ref_v).query(made.vertices)
    tol = 1e-9 * float(np.ptp(ref_v, axis=0).max())
    return np.where(d <= tol, i, -1)


def outside_depth(made: Made, w: World, orig: np.ndarray) -> float:
    """How far the skeleton leaves the shape, in local radii (max over points along its edges). On a
    neuron only the injected edges count: the traced nodes outside the decimated mesh are the mesh's."""
    e = made.edges
    if w.facts is not None:
        e = e[(orig[e] < 0).any(axis=1)]
        if not len(e):
            return 0.0
    r_v = _radius_at(made.vertices, w)
    pts, _ = _samples(made.vertices, e, 0.25 * np.minimum(r_v[e[:, 0]], r_v[e[:, 1]]))
    depth = np.asarray(w.depth(pts), float) / _radius_at(pts, w)
    depth = np.where(np.isfinite(depth), depth, 1e9)  # +inf: beyond the distance's reach, far out
    return float(depth.max()) if len(depth) else 0.0


def outside_seen(made: Made, w: World, orig: np.ndarray, params: Params = Params()) -> float:
    """How far the injected edges reach beyond the cloud's tolerance tau (coverage's, docs/metrics.md
    5.2), in the nearest reference radius: a part within tau of the cloud lies on the sampled surface
    for every measure, the cloud cannot show it out (a neuron's, sampled from a decimated mesh)."""
    e = made.edges[(orig[made.edges] < 0).any(axis=1)]
    if not len(e) or not len(w.cloud):
        return 0.0
    r_v = _radius_at(made.vertices, w)
    pts, _ = _samples(made.vertices, e, 0.25 * np.minimum(r_v[e[:, 0]], r_v[e[:, 1]]))
    tree = cKDTree(w.cloud)
    tau = params.coverage_tau_factor * float(np.median(tree.query(w.cloud, k=2)[0][:, 1]))
    d = (tree.query(pts)[0] - tau) / _radius_at(pts, w)
    return float(d.max())


def thin_share(w: World, params: Params) -> float:
    """The share of surface points on a part fewer than ``open_resolved_diameter`` spacings across
    (2 x its local radius over the cloud's spacing there, 16 nearest neighbours)."""
    ok = np.isfinite(w.local_radius)
    pts = w.cloud[ok]
    tree = cKDTree(pts)
    nn = tree.query(pts, k=2, workers=-1)[0][:, 1]
    idx = tree.query(pts, k=16, workers=-1)[1]
    spacing = np.median(nn[idx], axis=1)
    return float(np.mean(2.0 * w.local_radius[ok] / spacing < float(params.open_resolved_diameter)))


def unbounded_share(cloud: np.ndarray, w: World, params: Params) -> float:
    """The share of the reference curve's samples (half a local radius apart) that are unbounded
    (boundedness at most beta*) against ``cloud``, both in the cloud's normalization."""
    from ...geometry import Normalization
    from ...metrics.boundedness import boundedness

    rv, re, rr = w.ref
    pts, _ = _samples(np.asarray(rv, float), np.asarray(re, np.int64), 0.5 * np.minimum(rr[re[:, 0]], rr[re[:, 1]]))
    norm = Normalization.from_cloud(cloud, params.normalize_by, params.normalized_size)
    beta = boundedness(norm.apply(cloud), norm.apply(pts), params=params)
    return float(np.mean(~(beta > params.beta_star))) if len(beta) else 0.0


def sparse_drop(w: World, uniform: np.ndarray, params: Params = Params()) -> float:
    """How much the sparse part lowers the reference skeleton's boundedness: the share of its samples
    unbounded against the non-uniform cloud ``w.cloud`` less that against the ``uniform`` cloud of the
    same shape and size (the truth of ``sparse_boundedness``)."""
    return unbounded_share(w.cloud, w, params) - unbounded_share(uniform, w, params)


def _decimation_only(flag: np.ndarray, branch: np.ndarray | None, orig: np.ndarray, w: World) -> bool:
    """True when every flagged branch lies mostly on traced nodes outside the mesh (a neuron's)."""
    if w.facts is None or not flag.any() or branch is None:
        return False
    inside = np.asarray(w.facts.inside, bool)
    for b in np.unique(branch[flag]):
        members = (branch == b) if b >= 0 else flag
        known = orig[members & (orig >= 0)]
        if not len(known) or np.mean(inside[known]) >= 0.5:
            return False
    return True


def twig_kinds(made: Made, orig: np.ndarray, w: World, branch: np.ndarray) -> dict[int, str]:
    """Per branch id of ``branch`` (the evaluation's branch per vertex, -1 at junctions), "shown",
    "beyond" or "partly" by the traced nodes on it (``TWIG_OUT``); a branch with no traced node (all
    injected) is "shown": nothing of the traced skeleton lies beyond the cloud there."""
    out_r = np.asarray(w.facts.outside_radii, float)
    kinds: dict[int, str] = {}
    for b in np.unique(branch[branch >= 0]):
        known = orig[(branch == b) & (orig >= 0)]
        far = out_r[known] > TWIG_OUT
        kinds[int(b)] = "beyond" if len(known) and far.all() else "partly" if far.any() else "shown"
    return kinds


def _beyond_twigs(made: Made, orig: np.ndarray, w: World) -> int:
    """The terminal branches of the traced skeleton in ``made`` whose every own node lies more than
    ``TWIG_OUT`` traced radii out of the mesh."""
    from ...curve import CurveSkeleton
    from ...diagnostics.branches import decompose_branches

    curve = CurveSkeleton.from_raw(made.vertices, made.edges)
    br = decompose_branches(curve)
    deg = curve.degrees()
    out_r = np.asarray(w.facts.outside_radii, float)
    n = 0
    for b in br.terminal():
        own = [v for v in br.paths[b] if deg[v] <= 2]
        known = orig[np.asarray(own, np.int64)]
        n += int(len(own) > 0 and (known >= 0).all() and (out_r[known] > TWIG_OUT).all())
    return n


def _spurs_located(made: Made, orig: np.ndarray, flag: np.ndarray | None) -> bool | None:
    """Every injected spur (a component of the injected vertices) has a flagged vertex."""
    if flag is None:
        return None
    new = np.flatnonzero(orig < 0)
    e = made.edges[(orig[made.edges] < 0).all(axis=1)]
    n = len(made.vertices)
    g = coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n))
    _, comp = connected_components(g, directed=False)
    return all(flag[new[comp[new] == c]].any() for c in np.unique(comp[new]))


def along_surface_truth(made: Made, w: World) -> int | None:
    """1 for an offset skeleton moved at least ``SURF_YES`` local radii across its axis (the median over
    its vertices of the move's part perpendicular to the reference's tangent), 0 for the intact one or
    one moved at most ``SURF_NO``; None otherwise and on a neuron, where the check does not run
    (docs/diagnostics.md "Along the surface")."""
    if w.facts is not None or made.kind not in ("intact", "offset"):
        return None
    if made.kind == "intact":
        return 0
    v, e, r = (np.asarray(x, float) for x in w.ref)
    t = vertex_tangents(v, e.astype(np.int64))
    move = np.asarray(made.vertices, float) - v
    across = float(np.median(np.linalg.norm(move - np.sum(move * t, axis=1)[:, None] * t, axis=1) / r))
    return 1 if across >= SURF_YES else 0 if across <= SURF_NO else None


def row_truth(made: Made, w: World, condition: str, fired: set[str], arrays: dict[str, np.ndarray],
              first: bool, params: Params = Params(), drop: float | None = None) -> dict[str, Any]:
    """Truth per code (``truth_{code}``: 1, 0 or None) and the facts behind it for one skeleton;
    ``first``: the cloud's first (intact) skeleton, the only one counted for the cloud codes;
    ``drop``: :func:`sparse_drop` on a non-uniform cloud (``sparse_boundedness`` true from
    ``open_surface_share``, false under half that, left out in between; false on the other clouds)."""
    from ...diagnostics.record import DEFECT_BITS

    k = made.kind
    orig = origin(made, w.ref[0])
    vflags = arrays.get("curve_vertex_defects")
    if vflags is not None and len(vflags) != len(made.vertices):
        vflags = None
    branch = arrays.get("curve_vertex_branch")
    branch = branch if branch is not None and len(branch) == len(made.vertices) else None
    t: dict[str, Any] = {}
    skeleton_ok = k not in GLOBAL_KINDS and k != "no_correspondence"
    t["spurious_branches"] = (1 if k == "spurs" else 0) if skeleton_ok else None
    t["spurious_cycles"] = None if not skeleton_ok or k == "shortcut" else int(k == "chord_cycle")
    t["missing_cycles"] = int(k == "broken_cycle") if skeleton_ok else None
    if k == "broken":  # a cut through a ring opens it
        t["missing_cycles"] = cycles_cut(made, w)
    depth = outside_depth(made, w, orig) if k not in ("frame", "no_correspondence") else float("nan")
    t["outside"] = None if not np.isfinite(depth) else (1 if depth >= OUT_YES else 0 if depth <= OUT_NO else None)
    missing = uncovered_radii(made, w) if k not in ("frame", "no_correspondence") else float("nan")
    t["incomplete"] = None if not np.isfinite(missing) else (
        1 if missing > MISS_YES else 0 if missing < MISS_NO else None)
    seen = area = float("nan")
    if w.facts is not None:  # a neuron: a defect under what its cloud resolves is left out
        if t["outside"] == 1:
            seen = outside_seen(made, w, orig, params)
            t["outside"] = 1 if seen >= OUT_YES else None
        if t["incomplete"] == 1:
            area = uncovered_area(made, w)
            t["incomplete"] = 1 if area >= MISS_AREA else None
    t["along_surface"] = along_surface_truth(made, w)
    t["collapse"] = int(k == "collapse")
    t["frame"] = int(k == "frame")
    if first:
        thin = thin_share(w, params)
        t["outliers"] = int(condition == "outliers")
        t["open_surface"] = int(condition == "views") if (w.closed or condition == "views") else None
        t["thin_parts"] = 1 if thin >= params.thin_min_share else 0 if thin < 0.5 * params.thin_min_share else None
        share = float(params.open_surface_share)
        t["sparse_boundedness"] = 0 if condition != "nonuniform" else None if drop is None else (
            1 if drop >= share else 0 if drop < 0.5 * share else None)
    else:
        thin = float("nan")
        t.update(dict.fromkeys(("outliers", "open_surface", "thin_parts", "sparse_boundedness")))
    deg = np.bincount(made.edges.ravel(), minlength=len(made.vertices))
    t["trivial_smoothness"] = int(not (deg == 2).any())
    t["no_correspondence"] = int(made.skeletal is not None)
    located = None
    if t["outside"] == 0 and "outside" in fired and vflags is not None and \
            _decimation_only((vflags & DEFECT_BITS["outside"]) > 0, branch, orig, w):
        t["outside"] = None  # the mesh lost the twig: the cloud does not show it
    twigs: dict[str, Any] = dict.fromkeys(("twigs_beyond", "flagged_shown", "flagged_beyond", "flagged_partly"))
    if w.facts is not None and t["spurious_branches"] == 0:
        # the traced skeleton against the cloud: its twigs beyond the mesh are spurious there
        twigs["twigs_beyond"] = beyond = _beyond_twigs(made, orig, w)
        t["spurious_branches"] = int(beyond > 0)
        if "spurious_branches" in fired:
            t["spurious_branches"] = None
            if vflags is not None and branch is not None:
                flag = (vflags & DEFECT_BITS["spurious_branches"]) > 0
                kinds = twig_kinds(made, orig, w, np.where(flag, branch, -1))
                for k in ("shown", "beyond", "partly"):
                    twigs[f"flagged_{k}"] = sum(v == k for v in kinds.values())
                t["spurious_branches"] = 0 if twigs["flagged_shown"] else 1 if twigs["flagged_beyond"] else None
    if k == "spurs" and "spurious_branches" in fired:
        located = _spurs_located(made, orig, None if vflags is None else (vflags & DEFECT_BITS["spurious_branches"]) > 0)
    out = {f"truth_{c}": v for c, v in t.items()}
    pieces_flag = None if vflags is None else (vflags & DEFECT_BITS["disconnected"]) > 0
    out.update(disconnected_truth(made, w, orig, fired, pieces_flag))
    out.update(outside_depth=depth, outside_seen=seen, uncovered_radii=missing, uncovered_area=area, thin_share=thin,
               spurs_located=located, sparse_drop=float("nan") if drop is None or not first else drop, **twigs)
    return out
