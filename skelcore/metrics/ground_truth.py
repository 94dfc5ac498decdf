"""A curve skeleton against a ground-truth curve with a radius: the community's metrics
(docs/metrics.md 5.3.1 gives every formula and its source).

Both curves are cut into pieces of at most ``sample_step`` x the reference's smallest radius;
each piece's midpoint is a sample weighted by its length (isolated vertices are left out, unless a
curve has no edge). Distances are exact (nearest point on the other curve's edges); a sample's
local radius r is the reference radius at its nearest reference point (linear along edges; without
one, the median distance from each reference vertex to its ``radius_k`` nearest cloud points). Chamfer both ways (PRBonn/DiffTS); precision / recall / F1 at
thresholds t_k = k / K x ``threshold_max`` local radii, averaged over k = 1..K (DiffTS's curve
area, its thresholds in local radii); junctions (degree >= 3) and endpoints (degree 1) matched one
to one within ``match_radii`` x r of the reference node (PyNeval's branch/leaf metric: Hungarian,
scipy's linear_sum_assignment); cycle count error E - V + C; length ratio; branch split / merge
counts (branches: maximal chains through degree-2 vertices). Given how far each reference node lies
outside the surface the cloud was drawn from, precision / recall / F1 also on the held reference:
the samples owned by nodes within ``held_radii`` of their radii of it (5.3.1 "The held reference").
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ..correspondence import project_onto_curve
from ..curve import CurveSkeleton
from ..errors import SkelInputError
from ..params import Params
from .reference import graph_counts

__all__ = ["GroundTruthParams", "GroundTruthComparison", "compare_with_ground_truth", "curve_samples",
           "branch_labels", "match_nodes", "radius_from_cloud", "reference_radius", "ground_truth", "piece_shares"]

_MAX_SAMPLES = 200_000


@dataclass(frozen=True)
class GroundTruthParams:
    """The metrics' constants (docs/metrics.md 5.3.1), each the :class:`skelcore.Params` field of the
    same name with the ``gt_`` prefix (documented there); ``evaluate`` takes them from it
    (:meth:`from_params`)."""

    # the defaults are Params' gt_ fields (one source of truth for the constants)
    thresholds: int = Params.gt_thresholds
    threshold_max: float = Params.gt_threshold_max
    match_radii: float = Params.gt_match_radii
    branch_radii: float = Params.gt_branch_radii
    sample_step: float = Params.gt_sample_step
    radius_k: int = Params.gt_radius_k
    held_radii: float = Params.gt_held_radii

    def __post_init__(self) -> None:
        for name in ("threshold_max", "match_radii", "branch_radii", "sample_step"):
            if not float(getattr(self, name)) > 0:
                raise ValueError(f"ground-truth parameter {name}={getattr(self, name)!r}: must be > 0")
        for name in ("thresholds", "radius_k"):
            if int(getattr(self, name)) < 1:
                raise ValueError(f"ground-truth parameter {name}={getattr(self, name)!r}: must be a positive integer")
        if not float(self.held_radii) >= 0:
            raise ValueError(f"ground-truth parameter held_radii={self.held_radii!r}: must be >= 0")

    @classmethod
    def from_params(cls, params) -> "GroundTruthParams":
        """The ``gt_`` fields of a :class:`skelcore.Params`."""
        return cls(**{f: getattr(params, f"gt_{f}") for f in cls.__dataclass_fields__})


@dataclass(frozen=True)
class GroundTruthComparison:
    """Scores of a curve against a reference; distances in the inputs' units, counts as
    (ours, reference[, matched]); NaN where a ratio has nothing to count (no junctions, say). The
    ``held_`` fields: None unless the reference's nodes' distances outside the surface were given
    (``held_nodes`` = (held, all) reference vertices, ``held_share`` the held share of its length)."""

    chamfer: float
    chamfer_to_reference: float
    chamfer_from_reference: float
    chamfer_radii: float
    precision: float
    recall: float
    f1: float
    junction_precision: float
    junction_recall: float
    endpoint_precision: float
    endpoint_recall: float
    junctions: tuple[int, int, int]
    endpoints: tuple[int, int, int]
    cycles: tuple[int, int]
    cycle_error: int
    length: tuple[float, float]
    length_ratio: float
    branches: tuple[int, int]
    splits: int
    merges: int
    thresholds: tuple[float, ...]
    match_radii: float
    branch_radii: float
    radius_source: str
    held_precision: float | None = None
    held_recall: float | None = None
    held_f1: float | None = None
    held_share: float | None = None
    held_nodes: tuple[int, int] | None = None
    held_radii: float | None = None

    def to_dict(self) -> dict:
        d = asdict(self)
        return {k: list(v) if isinstance(v, tuple) else v for k, v in d.items()}

    @classmethod
    def from_dict(cls, d: dict) -> "GroundTruthComparison":
        """The inverse of :meth:`to_dict` (lists back to tuples; JSON's null back to NaN; a ``held_``
        field absent or null stays None)."""
        out = {}
        for name, f in cls.__dataclass_fields__.items():
            if name.startswith("held_") and d.get(name) is None:
                continue
            v = d[name]
            if isinstance(v, list):
                v = tuple(v)
            elif v is None or (isinstance(v, str) and f.type == "float"):
                v = {"inf": float("inf"), "-inf": float("-inf")}.get(v, float("nan"))
            out[name] = v
        return cls(**out)


def curve_samples(curve: CurveSkeleton, step: float, radius: np.ndarray | None = None):
    """Piece midpoints (every edge cut into ceil(L / step) equal pieces), their weights (piece
    lengths), their edge, and the radius interpolated at them (when ``radius`` per vertex is given).
    A curve without edges gives its vertices, weight 1 each, edge -1."""
    v, e = curve.vertices, curve.edges
    if len(e) == 0:
        r = None if radius is None else np.asarray(radius, float).copy()
        return v.copy(), np.ones(len(v)), np.full(len(v), -1, dtype=np.int64), r
    a, b = v[e[:, 0]], v[e[:, 1]]
    length = np.linalg.norm(b - a, axis=1)
    n = np.maximum(np.ceil(length / step).astype(np.int64), 1)
    edge = np.repeat(np.arange(len(e)), n)
    start = np.concatenate([[0], np.cumsum(n)[:-1]])
    t = (np.arange(len(edge)) - start[edge] + 0.5) / n[edge]
    pts = a[edge] + t[:, None] * (b - a)[edge]
    r = None
    if radius is not None:
        radius = np.asarray(radius, float)
        r = radius[e[edge, 0]] + t * (radius[e[edge, 1]] - radius[e[edge, 0]])
    return pts, (length / n)[edge], edge, r


def branch_labels(curve: CurveSkeleton) -> tuple[np.ndarray, int]:
    """Branch index of every edge: edges sharing a vertex of degree 2 are in one branch, so a branch
    is a maximal chain between vertices of other degrees (a loop of degree-2 vertices is one)."""
    e = curve.edges
    if len(e) == 0:
        return np.empty(0, dtype=np.int64), 0
    deg = curve.degrees()
    inc_v = e.ravel()
    inc_e = np.repeat(np.arange(len(e)), 2)
    two = deg[inc_v] == 2
    order = np.argsort(inc_v[two], kind="stable")
    pairs = inc_e[two][order].reshape(-1, 2)
    adj = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(e), len(e)))
    n, labels = connected_components(adj, directed=False)
    return labels.astype(np.int64), int(n)


def match_nodes(ours: np.ndarray, ref: np.ndarray, reach: np.ndarray) -> int:
    """Largest one-to-one matching of points ``ours`` to ``ref`` with |p - q| <= reach[q] (ties
    broken by the smallest total distance): the number of matched pairs."""
    if len(ours) == 0 or len(ref) == 0:
        return 0
    d = np.linalg.norm(ours[:, None, :] - ref[None, :, :], axis=2)
    allowed = d <= reach[None, :] * (1.0 + 1e-9)
    big = 1.0 + float(d[allowed].sum()) if allowed.any() else 1.0
    rows, cols = linear_sum_assignment(np.where(allowed, d, big))
    return int(np.count_nonzero(allowed[rows, cols]))


def radius_from_cloud(vertices: np.ndarray, cloud: np.ndarray, k: int) -> np.ndarray:
    """Median distance from each vertex to its ``k`` nearest cloud points (the inscribed radius of
    an exact skeleton point; the median resists noise and stray points)."""
    k = max(1, min(int(k), len(cloud)))
    d, _ = cKDTree(cloud).query(vertices, k=k, workers=-1)
    return np.median(np.asarray(d).reshape(len(vertices), k), axis=1)


def _ratio(num: int, den: int) -> float:
    return float(num) / den if den else float("nan")


def _edges_only(curve: CurveSkeleton) -> CurveSkeleton:
    """The curve without its isolated vertices (a curve with edges is the union of its edges)."""
    if curve.n_edges == 0:
        return curve
    used = np.unique(curve.edges)
    if len(used) == curve.n_vertices:
        return curve
    remap = np.full(curve.n_vertices, -1)
    remap[used] = np.arange(len(used))
    return CurveSkeleton(vertices=curve.vertices[used], edges=remap[curve.edges], vertex_map=curve.vertex_map[used])


def _at_vertices(vertices: np.ndarray, values: np.ndarray, q: np.ndarray, edge: np.ndarray):
    """An output array for points q on edges ``edge``, filled where q is a vertex (edge -1) with the
    value of its nearest vertex; returns it and that mask (the caller fills the rest along edges)."""
    out = np.empty(len(q))
    iso = edge < 0
    if iso.any():
        _, nearest = cKDTree(vertices).query(q[iso], k=1)
        out[iso] = values[nearest]
    return out, iso


def _at_projection(curve: CurveSkeleton, radius: np.ndarray, q: np.ndarray, edge: np.ndarray) -> np.ndarray:
    """The radius, linear along each edge, at points q lying on the given edges (-1: a vertex)."""
    out, iso = _at_vertices(curve.vertices, radius, q, edge)
    e = curve.edges[edge[~iso]]
    a, b = curve.vertices[e[:, 0]], curve.vertices[e[:, 1]]
    ab = b - a
    t = np.einsum("ij,ij->i", q[~iso] - a, ab) / np.maximum(np.einsum("ij,ij->i", ab, ab), 1e-300)
    t = np.clip(t, 0.0, 1.0)
    out[~iso] = radius[e[:, 0]] + t * (radius[e[:, 1]] - radius[e[:, 0]])
    return out


def compare_with_ground_truth(curve: CurveSkeleton, reference: CurveSkeleton, reference_radius: np.ndarray | None = None,
                              cloud: np.ndarray | None = None, *, params: GroundTruthParams | None = None,
                              outside_radii: np.ndarray | None = None) -> GroundTruthComparison:
    """Score ``curve`` against ``reference`` (same frame and units); ``reference_radius`` per reference
    vertex, else estimated from ``cloud`` (one of them is needed); ``outside_radii`` per reference
    vertex (how far outside the cloud's surface, in its radii; 0 inside) adds the ``held_`` scores.
    Module docstring and docs/metrics.md 5.3.1 for the definitions."""
    p = params or GroundTruthParams()
    held = _held_nodes(outside_radii, reference, p.held_radii)
    if reference.n_edges == 0:
        raise SkelInputError("the reference curve has no edges")
    if reference_radius is not None:
        radius = np.asarray(reference_radius, float).ravel()
        if radius.shape != (reference.n_vertices,):
            raise SkelInputError(f"reference radius has {radius.size} values for {reference.n_vertices} vertices")
        source = "reference"
    elif cloud is not None and len(cloud):
        radius = radius_from_cloud(reference.vertices, np.asarray(cloud, float), p.radius_k)
        source = "cloud"
    else:
        raise SkelInputError("ground-truth metrics need the reference's radius or the cloud to estimate it")
    if not (np.all(np.isfinite(radius)) and np.all(radius > 0)):
        raise SkelInputError("reference radius must be finite and > 0 at every vertex")
    radius = radius[np.unique(reference.edges)]
    held = None if held is None else held[np.unique(reference.edges)]
    reference = _edges_only(reference)

    lengths = (float(curve.edge_lengths().sum()) if curve.n_edges else 0.0, float(reference.edge_lengths().sum()))
    step = max(p.sample_step * float(radius.min()), sum(lengths) / _MAX_SAMPLES)
    ref_pts, ref_w, ref_edge, ref_r = curve_samples(reference, step, radius)
    our_pts, our_w, our_edge, _ = curve_samples(curve, step)
    q, qe = project_onto_curve(our_pts, reference)
    d_ours = np.linalg.norm(q - our_pts, axis=1)
    r_ours = _at_projection(reference, radius, q, qe)
    q2, _ = project_onto_curve(ref_pts, _edges_only(curve))
    d_ref = np.linalg.norm(q2 - ref_pts, axis=1)

    def wmean(x, w):
        return float(np.sum(x * w) / np.sum(w))

    thresholds = p.threshold_max * np.arange(1, p.thresholds + 1) / p.thresholds
    slack = 1.0 + 1e-9  # "within" holds up to rounding: a sample exactly at a threshold counts
    prec = np.array([wmean(d_ours <= t * slack * r_ours, our_w) for t in thresholds])
    rec = np.array([wmean(d_ref <= t * slack * ref_r, ref_w) for t in thresholds])
    f1 = np.where(prec + rec > 0, 2 * prec * rec / np.where(prec + rec > 0, prec + rec, 1.0), 0.0)

    deg_o, deg_r = curve.degrees(), reference.degrees()
    counts = {}
    for kind, sel_o, sel_r in (("junctions", deg_o >= 3, deg_r >= 3), ("endpoints", deg_o == 1, deg_r == 1)):
        m = match_nodes(curve.vertices[sel_o], reference.vertices[sel_r], p.match_radii * radius[sel_r])
        counts[kind] = (int(sel_o.sum()), int(sel_r.sum()), m)

    splits, merges, n_branches = _splits_merges(curve, reference, radius, p.branch_radii,
                                                (ref_pts, ref_w, ref_edge, ref_r, d_ref), our_pts, our_edge)
    cyc_o, cyc_r = graph_counts(curve)["cycles"], graph_counts(reference)["cycles"]
    c_to, c_from = wmean(d_ours, our_w), wmean(d_ref, ref_w)
    held_scores = {} if held is None else _held_scores(
        reference, held, step, (q, qe, d_ours, r_ours, our_w), (d_ref, ref_r, ref_w), thresholds * slack,
        float(p.held_radii))
    return GroundTruthComparison(
        chamfer=(c_to + c_from) / 2, chamfer_to_reference=c_to, chamfer_from_reference=c_from,
        chamfer_radii=(wmean(d_ours / r_ours, our_w) + wmean(d_ref / ref_r, ref_w)) / 2,
        precision=float(prec.mean()), recall=float(rec.mean()), f1=float(f1.mean()),
        junction_precision=_ratio(counts["junctions"][2], counts["junctions"][0]),
        junction_recall=_ratio(counts["junctions"][2], counts["junctions"][1]),
        endpoint_precision=_ratio(counts["endpoints"][2], counts["endpoints"][0]),
        endpoint_recall=_ratio(counts["endpoints"][2], counts["endpoints"][1]),
        junctions=counts["junctions"], endpoints=counts["endpoints"],
        cycles=(cyc_o, cyc_r), cycle_error=cyc_o - cyc_r,
        length=lengths, length_ratio=lengths[0] / lengths[1] if lengths[1] > 0 else float("nan"),
        branches=n_branches, splits=splits, merges=merges,
        thresholds=tuple(float(t) for t in thresholds), match_radii=float(p.match_radii),
        branch_radii=float(p.branch_radii), radius_source=source, **held_scores,
    )


def _held_nodes(outside_radii: np.ndarray | None, reference: CurveSkeleton, tolerance: float) -> np.ndarray | None:
    """Per reference vertex: inside the cloud's surface or at most ``tolerance`` of its radii outside."""
    if outside_radii is None:
        return None
    out = np.asarray(outside_radii, float).ravel()
    if out.shape != (reference.n_vertices,):
        raise SkelInputError(f"the reference's outside distances have {out.size} values for {reference.n_vertices} vertices")
    if not (np.all(np.isfinite(out)) and np.all(out >= 0)):
        raise SkelInputError("the reference's outside distances must be finite and >= 0 (0: inside)")
    return out <= tolerance


def piece_shares(curve: CurveSkeleton, step: float, node_weight: np.ndarray) -> np.ndarray:
    """Per sample of :func:`curve_samples` (same ``step``), the ``node_weight`` of the edge's end
    nearer to it (each vertex owns the half of each of its edges next to it; a piece midway between
    both ends gets their mean). A curve without edges: the vertices' own."""
    node_weight = np.asarray(node_weight, float)
    e = curve.edges
    if len(e) == 0:
        return node_weight.copy()
    n = np.maximum(np.ceil(curve.edge_lengths() / step).astype(np.int64), 1)
    edge = np.repeat(np.arange(len(e)), n)
    i = np.arange(len(edge)) - np.concatenate([[0], np.cumsum(n)[:-1]])[edge]
    side = np.sign(2 * i + 1 - n[edge])  # -1: first half, 0: the middle piece, +1: second half
    a, b = node_weight[e[edge, 0]], node_weight[e[edge, 1]]
    return np.where(side < 0, a, np.where(side > 0, b, (a + b) / 2))


def _projection_shares(reference: CurveSkeleton, node_weight: np.ndarray, q: np.ndarray, edge: np.ndarray) -> np.ndarray:
    """``node_weight`` of the reference vertex nearer to each projection q along its edge ``edge``
    (-1: q is a vertex, its own); midway, the two ends' mean."""
    node_weight = np.asarray(node_weight, float)
    out, iso = _at_vertices(reference.vertices, node_weight, q, edge)
    e = reference.edges[edge[~iso]]
    da = np.linalg.norm(q[~iso] - reference.vertices[e[:, 0]], axis=1)
    db = np.linalg.norm(q[~iso] - reference.vertices[e[:, 1]], axis=1)
    a, b = node_weight[e[:, 0]], node_weight[e[:, 1]]
    out[~iso] = np.where(da < db, a, np.where(db < da, b, (a + b) / 2))
    return out


def _held_scores(reference, held, step, ours, refs, limits, tolerance) -> dict:
    """Precision / recall / F1 on the held reference (docs/metrics.md 5.3.1 "The held reference"):
    the reference samples owned by held vertices, and our samples whose nearest reference point is."""
    q, qe, d_ours, r_ours, our_w = ours
    d_ref, ref_r, ref_w = refs
    h_ref = ref_w * piece_shares(reference, step, held)
    h_ours = our_w * _projection_shares(reference, held, q, qe)
    share = float(h_ref.sum() / ref_w.sum())

    def mean_hits(d, r, w):
        return np.array([np.sum(w * (d <= t * r)) / np.sum(w) if np.sum(w) > 0 else np.nan for t in limits])

    prec, rec = mean_hits(d_ours, r_ours, h_ours), mean_hits(d_ref, ref_r, h_ref)
    with np.errstate(invalid="ignore"):
        f1 = np.where(prec + rec > 0, 2 * prec * rec / np.where(prec + rec > 0, prec + rec, 1.0), 0.0)
    f1 = np.where(np.isnan(prec) | np.isnan(rec), np.nan, f1)
    return {"held_precision": float(prec.mean()), "held_recall": float(rec.mean()), "held_f1": float(f1.mean()),
            "held_share": share, "held_nodes": (int(held.sum()), int(len(held))), "held_radii": tolerance}


def _splits_merges(curve, reference, radius, reach, ref_samples, our_pts, our_edge):
    """Reference branch b and our branch c are associated when at least ``reach`` x (b's mean
    radius) of b's length lies within ``reach`` local radii of c (c: the branch of the nearest of our
    samples), reference samples within ``reach`` x r_J of a reference junction J left out (there every
    branch meets every other). splits = sum over b of (#c - 1)+, merges = sum over c of (#b - 1)+."""
    ref_pts, ref_w, ref_edge, ref_r, d_ref = ref_samples
    lab_r, n_r = branch_labels(reference)
    lab_o, n_o = branch_labels(curve)
    if n_o == 0:
        return 0, 0, (0, n_r)
    junction = np.flatnonzero(reference.degrees() >= 3)
    keep = d_ref <= reach * ref_r * (1.0 + 1e-9)
    if len(junction):
        dj, j = cKDTree(reference.vertices[junction]).query(ref_pts, k=1)
        keep &= dj > reach * radius[junction[j]]
    _, nearest = cKDTree(our_pts).query(ref_pts[keep], k=1)
    b = lab_r[ref_edge[keep]]
    c = lab_o[our_edge[nearest]]
    overlap = coo_matrix((ref_w[keep], (b, c)), shape=(n_r, n_o)).toarray()
    mean_r = np.bincount(lab_r[ref_edge], weights=ref_w * ref_r, minlength=n_r) / np.bincount(
        lab_r[ref_edge], weights=ref_w, minlength=n_r)
    assoc = overlap >= reach * mean_r[:, None]
    per_b, per_c = assoc.sum(axis=1), assoc.sum(axis=0)
    return int(np.maximum(per_b - 1, 0).sum()), int(np.maximum(per_c - 1, 0).sum()), (n_o, n_r)


def reference_radius(reference: CurveSkeleton, given: np.ndarray | None, cloud: np.ndarray | None,
                     k: int) -> tuple[np.ndarray | None, str]:
    """The reference's radius per vertex and where it came from: ``given`` (its file's radius) where
    finite and > 0, the cloud's estimate (:func:`radius_from_cloud`) elsewhere; "reference", "cloud"
    or "reference+cloud". (None, "") when neither is there."""
    r = None if given is None else np.asarray(given, float).ravel().copy()
    if r is not None and r.shape != (reference.n_vertices,):
        raise SkelInputError(f"reference radius has {r.size} values for {reference.n_vertices} vertices")
    known = np.zeros(reference.n_vertices, bool) if r is None else np.isfinite(r) & (r > 0)
    if known.all():
        return r, "reference"
    if cloud is None or not len(cloud):
        return None, ""
    if r is None:
        r = np.full(reference.n_vertices, np.nan)
    r[~known] = radius_from_cloud(reference.vertices[~known], np.asarray(cloud, float), k)
    return r, "reference+cloud" if known.any() else "cloud"


def ground_truth(curve: CurveSkeleton, reference: CurveSkeleton, cloud: np.ndarray | None, params,
                 radius: np.ndarray | None = None, outside_radii: np.ndarray | None = None) -> GroundTruthComparison:
    """What ``evaluate`` computes (its "ground truth" stage): :func:`compare_with_ground_truth` with the
    ``gt_`` constants of a :class:`skelcore.Params`, the radius from ``radius`` (else the reference's
    own) completed from the cloud (:func:`reference_radius`); all in the inputs' units.
    ``outside_radii``: the reference's facts, for the held scores (``skelcore evaluate --reference-facts``)."""
    p = GroundTruthParams.from_params(params)
    given = reference.radius if radius is None else radius
    r, source = reference_radius(reference, given, cloud, p.radius_k)
    out = compare_with_ground_truth(curve, reference, r, cloud, params=p, outside_radii=outside_radii)
    return out if source in ("", out.radius_source) else replace(out, radius_source=source)
