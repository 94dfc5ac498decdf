"""Missing parts: the parts of the shape a skeleton does not reach, and its completeness
(docs/diagnostics.md "Missing parts", "Completeness").

A cloud point is explained when a skeleton element's medial ball, grown by the coverage slack,
reaches it (docs/metrics.md 5.2, :mod:`skelcore.metrics.coverage`); completeness is the share explained. The
unexplained points are linked into regions of the cloud (neighbours closer than
``missing_link_factor`` median spacings). A region's depth is how far it reaches beyond its border
(the unexplained points next to explained ones), in the radius of that border: a contraction that
stops a radius short of a rounded end leaves a cap about one radius deep, a missing arm or half
handle reaches several, the wide sides of a flat part a curve crosses reach less than their width.
A region counts (warning ``incomplete``) when depth >= ``missing_depth`` and it holds
``missing_min_share`` of the cloud, or depth >= ``missing_small_depth`` and it holds the surface of
``missing_min_area`` squared median ball radii (one branch of an arbor is a small share of it), or
share >= ``missing_large_share``; it also fires when the completeness is under ``missing_min_completeness``.
A region beside a branch (an off-centre axis's far wall, a flat tube's sides: :mod:`.beside`) does not
count, and that floor reads it as explained. Above ``missing_max_points`` cloud points the work runs on a
random subsample, every cloud point taking its nearest sample's verdict (``subsample`` says so).
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field, replace
from typing import Callable

import numpy as np
from scipy.spatial import cKDTree

from ..correspondence import densify_curve
from ..curve import CurveSkeleton
from ..geometry import Checkpoint, kd_tree, no_checkpoint, query_workers, unique_rows
from ..metrics.cloud_index import CloudIndex, kept_index
from ..metrics.components import undirected_components
from ..metrics.coverage import Coverage, coverage, coverage_tau
from ..metrics.point_passes import nearest_squared
from ..metrics.region_links import region_links
from ..params import Params
from .beside import beside_regions
from .chord_cache import ChordCache
from .spur_cache import find_rows, row_hash, row_words
from .trust_warning import TrustWarning

__all__ = ["MissingRegion", "MissingParts", "missing_parts", "skeleton_elements", "coverage_elements", "depth_clause",
           "coverage_holds", "explained_alone", "completeness_alone"]

# neighbours per unexplained point in the region graph (edges also need to be shorter than the link)
LINK_K = 8
# border points closer than this many links are one piece of a region's border
BORDER_LINK = 3.0
# above missing_max_points, cloud points within this many (subsample) spacings of an unexplained sample
# look up their nearest sample's verdict
SPREAD = 4.0
#: cloud rows spread per call between two checkpoints (about 0.1 s at 1M points)
SPREAD_CHUNK = 131_072
# elements whose distance to the cloud gives the median ball radius of missing_min_area
SMALL_ELEMENTS = 20_000
# regions under missing_min_share with fewer points are not measured (no tree is built for them)
SMALL_FEWEST = 8
# the area rule's kept element distances (_element_distances): every element asked the first time when the
# subsample takes one of at most this many; at most this many rows kept per tree, for the last this many trees
_SMALL_EVERY = 2
_SMALL_ROWS = 400_000
_SMALL_TREES = 2
_SMALL_KEPT: list[tuple] = []
_SMALL_LOCK = threading.Lock()
# at most this many regions are tried beside a branch (_mark_beside), the counted ones first
BESIDE_REGIONS = 64
# seed of the subsample taken above missing_max_points (the verdicts must not depend on a run)
SUBSAMPLE_SEED = 0
# unexplained points whose neighbours the kept search does not settle are searched among the unexplained
# points near them while they are at most this share of all (_near_rows), else in a tree of all
NEAR_ROWS_SHARE = 0.25
# a region's depth quantile: from this many points the distances to its border are searched only where
# the bounds from QUANTILE_CENTRES of the border points leave them near the quantile (_quantile_distance)
QUANTILE_FEWEST = 2048
QUANTILE_CENTRES = 16
# up to this many (point, border point) pairs the depth's distances are taken pair by pair in one compiled
# pass (_border_distance; about 1.5 ns a pair), beyond it from a tree of the border
BORDER_PAIRS = 4_000_000


@dataclass
class MissingRegion:
    """One connected region of unexplained cloud points.

    ``share``: its share of the cloud; ``depth``: how far it reaches beyond its border (``reach``, the
    quantile distance to the border, normalized units) in the border's radius ``border_radius``; NaN
    for regions under both ``missing_min_share`` and ``missing_min_area``, inf for a region no
    explained point touches; ``centroid`` in the units of ``to_user`` (user units in an evaluation);
    ``deepest``: the cloud row farthest from the skeleton's balls; ``counted``: a missing part
    (``incomplete``); ``beside``: it lies beside a branch, within its cross-section (:mod:`.beside`),
    and does not count whatever its size."""

    id: int
    n_points: int
    share: float
    depth: float
    reach: float
    border_radius: float
    centroid: np.ndarray
    deepest: int
    counted: bool
    beside: bool = False

    def to_dict(self) -> dict:
        return {"id": self.id, "n_points": self.n_points, "share": self.share, "depth": self.depth,
                "reach": self.reach, "border_radius": self.border_radius,
                "centroid": [float(c) for c in self.centroid], "deepest_point": self.deepest,
                "counted": self.counted, "beside": self.beside}


@dataclass
class MissingParts:
    """What of the cloud a skeleton explains (docs/diagnostics.md "Missing parts").

    Per cloud point: ``explained`` (bool) and ``region`` (int32: the id of its region in ``regions``,
    -1 when explained); ``missing`` flags the points of counted regions. ``regions`` are sorted by
    share, largest first. ``subsample``: the number of cloud points the regions were found on, None
    when all were used."""

    completeness: float
    explained: np.ndarray
    region: np.ndarray
    regions: list[MissingRegion]
    n_elements: int
    subsample: int | None
    what: str = "skeleton"
    thresholds: dict = field(default_factory=dict)
    outside_elements: int = 0

    @property
    def beside_share(self) -> float:
        """The share of the cloud in regions beside a branch (:mod:`.beside`): unexplained, not missing."""
        return float(sum(r.share for r in self.regions if r.beside))

    @property
    def counted(self) -> list[MissingRegion]:
        return [r for r in self.regions if r.counted]

    @property
    def incomplete(self) -> bool:
        """Some region counts, or the skeleton explains under ``missing_min_completeness`` of the cloud, the
        regions beside a branch counted as explained."""
        floor = self.thresholds.get("missing_min_completeness", 0.0)
        return bool(self.counted) or self.completeness + self.beside_share < floor

    @property
    def missing(self) -> np.ndarray:
        return self.missing_region() >= 0

    def missing_region(self) -> np.ndarray:
        """Per cloud point, the id of its region when that region counts, else -1 (int64): a table of the
        regions (-1 last) read at each point's region, not a search of the counted ids (at 1M points
        10.6 -> 2.8 ms, in the update's serial tail; docs/performance.md 6.10)."""
        table = np.full(len(self.regions) + 1, -1, np.int64)
        ids = [r.id for r in self.counted]
        table[ids] = ids
        return table[np.asarray(self.region)]

    @property
    def missing_share(self) -> float:
        return float(sum(r.share for r in self.counted))

    def to_dict(self, max_regions: int = 10) -> dict:
        """Completeness, the counted regions and the largest others (at most ``max_regions`` in all)."""
        shown = self.counted + [r for r in self.regions if not r.counted][: max(0, max_regions - len(self.counted))]
        return {"completeness": self.completeness, "incomplete": self.incomplete, "missing_share": self.missing_share,
                "n_missing_parts": len(self.counted), "n_regions": len(self.regions), "beside_share": self.beside_share,
                "regions": [r.to_dict() for r in shown], "n_elements": self.n_elements,
                "subsample": self.subsample, "thresholds": dict(self.thresholds)}

    def warnings(self) -> list[TrustWarning]:
        """``incomplete`` when some region counts, with its share, depth and place."""
        parts = self.counted
        if not self.incomplete:
            return []
        sub = f" (found on {self.subsample:,} sampled cloud points)" if self.subsample else ""
        if not parts:
            big = f", the largest {self.regions[0].share:.1%} of it" if self.regions else ""
            return [TrustWarning(
                "incomplete",
                f"the {self.what} explains only {self.completeness:.1%} of the cloud (completeness "
                f"{self.completeness:.3f}; {len(self.regions)} unexplained regions{big}){sub}",
            )]  # fmt: skip
        said = "; ".join(f"{r.share:.1%} of the cloud around ({r.centroid[0]:.4g}, {r.centroid[1]:.4g}, "
                         f"{r.centroid[2]:.4g}){depth_clause(r.depth)}" for r in parts[:3])
        more = f" and {len(parts) - 3} more" if len(parts) > 3 else ""
        n = len(parts)
        return [TrustWarning(
            "incomplete",
            f"the {self.what} does not reach {n} part{'s' if n > 1 else ''} of the shape: {said}{more}; "
            f"completeness {self.completeness:.3f}{sub}",
        )]  # fmt: skip


def depth_clause(depth: float | str | None, beyond: str = "it") -> str:
    """How far a region reaches, in words when it is no number: inf (``"inf"`` as the JSON writes it)
    when no explained point borders it, NaN or None when too small to be measured (the clause is left out)."""
    depth = np.nan if depth is None else float(depth)
    if depth == np.inf:
        return " with no explained point next to it"
    if not np.isfinite(depth):
        return ""
    return f" reaching {depth:.2g} local radii beyond {beyond}"


def skeleton_elements(skeleton: np.ndarray | CurveSkeleton, spacing: float, max_elements: int,
                      checkpoint: Checkpoint = no_checkpoint) -> np.ndarray:
    """The points whose balls explain the cloud: a curve's vertices and points every ``spacing``
    along its edges (at most 200,000, as the evaluation's curve coverage), or a point set's distinct
    points; more than ``max_elements`` are thinned to one per grid cell, of ``spacing / 2`` grown
    until at most ``max_elements`` remain (contracted sets are tubes of points, not curves), after
    a random pick of 10 x ``max_elements`` from a larger set."""
    if isinstance(skeleton, CurveSkeleton):
        total = float(skeleton.edge_lengths().sum())
        step = max(spacing, total / 200_000, 1e-12)
        pts, _ = densify_curve(skeleton, step)
        return np.vstack([pts, skeleton.vertices])
    pts = np.asarray(skeleton, dtype=float).reshape(-1, 3)
    if len(pts) <= max_elements or not spacing > 0:
        return unique_rows(pts, checkpoint)[0]
    if len(pts) > 10 * max_elements:  # a random tenth-or-less first: the cells see no difference
        pts = pts[np.random.default_rng(SUBSAMPLE_SEED).choice(len(pts), 10 * max_elements, replace=False)]
    cell = spacing / 2
    lo = pts.min(axis=0)
    while True:
        cells = np.floor((pts - lo) / cell).astype(np.int64)
        dims = cells.max(axis=0) + 1
        key = (cells[:, 0] * dims[1] + cells[:, 1]) * dims[2] + cells[:, 2]  # one number per cell
        _, first = np.unique(key, return_index=True)
        checkpoint(0.0)
        if len(first) <= max_elements:
            return pts[np.sort(first)]
        cell *= 1.5


def coverage_elements(skeleton: np.ndarray | CurveSkeleton, pts: np.ndarray, spacing: float, p: Params,
                      inside: Callable[[np.ndarray], np.ndarray] | None,
                      checkpoint: Checkpoint = no_checkpoint) -> tuple[np.ndarray, int]:
    """The elements whose balls explain the points ``pts`` (:func:`skeleton_elements` every ``spacing``),
    without those ``inside`` rejects as in the air (:func:`_in_air`), and how many it rejected."""
    elements = skeleton_elements(skeleton, spacing, int(p.missing_max_elements), checkpoint)
    if inside is None or not len(elements):
        return elements, 0
    ok = ~_in_air(elements, inside, pts, p)
    return elements[ok], int(np.count_nonzero(~ok))


def _identity(points: np.ndarray) -> np.ndarray:
    return points


def missing_parts(
    cloud: np.ndarray,
    skeleton: np.ndarray | CurveSkeleton,
    params: Params = Params(),
    *,
    cov: Coverage | None = None,
    tau: float | None = None,
    what: str = "skeleton",
    to_user: Callable[[np.ndarray], np.ndarray] = _identity,
    keep: np.ndarray | None = None,
    inside: Callable[[np.ndarray], np.ndarray] | None = None,
    cloud_tree: Callable[[np.ndarray], cKDTree] | None = None,
    coverage_of: Callable[[np.ndarray, np.ndarray, float, CloudIndex], Coverage] | None = None,
    nearest_sample: Callable[[np.ndarray, np.ndarray, Checkpoint], tuple[np.ndarray, np.ndarray]] | None = None,
    neighbours: Callable[[cKDTree, np.ndarray, int, float], tuple[np.ndarray, np.ndarray]] | None = None,
    sampled: Callable[[np.ndarray, Params], tuple[np.ndarray | None, CloudIndex, Callable[[Checkpoint], float]]]
    | None = None,
    chords: ChordCache | None = None,
    checkpoint: Checkpoint = no_checkpoint,
) -> MissingParts:
    """The parts of the (normalized) cloud the (normalized) skeleton does not reach, and its completeness.

    Parameters
    ----------
    cloud : (N, 3) normalized cloud.
    skeleton : a skeletal point set (M, 3), curve samples, or a :class:`CurveSkeleton` (its edges
        densified as the evaluation's curve coverage does), normalized.
    cov : the evaluation's :class:`Coverage` of these elements, if computed (then used as is; when it
        was estimated on a subsample, the regions are found on that subsample and spread, the
        completeness is its covered share); else computed here.
    tau : the coverage tolerance of the full cloud (``coverage_tau``), if known.
    what : how the warning names the skeleton ("curve skeleton", "skeletal point set").
    to_user : maps normalized points to user units for the regions' centroids.
    keep : for a point set, the rows whose balls may explain the cloud (e.g. the bounded ones: the
        ball of a point far outside the shape touches it from outside and "explains" it); ignored
        when ``cov`` is given.
    inside : a test of normalized points, True in the shape (e.g. the voxelized interior): the
        elements it rejects explain nothing (an edge through the air touches the cloud from outside
        with balls as large as the gap it crosses; docs/diagnostics.md "Completeness"). When it
        rejects some, the coverage is computed again without them (``cov`` is not used) and
        ``outside_elements`` counts them.
    cloud_tree : ``cloud_tree(points)`` gives ``cKDTree(points)`` of the points the regions are found
        on (the cloud or its subsample, not an estimated ``cov``'s sample), kept by the caller (an
        edit's update asks about the same points each time); else built here.
    coverage_of : ``coverage_of(points, elements, tau, index)`` gives ``coverage(points, elements,
        params, tau, index=index)`` when the coverage is computed here (an edit's update gives it by
        difference from the curve edited, skelcore/edit/missing_update.py); else computed as is.
    nearest_sample : ``nearest_sample(cloud, points, checkpoint)`` gives each cloud point's distance
        and row of its nearest point of the subsample ``points`` (``cloud_tree(points).query(cloud)``),
        kept by the caller: the spread then reads it instead of searching (:func:`_spread`).
    neighbours : ``neighbours(tree, rows, k, link)`` gives ``tree.query(points[rows], k,
        distance_upper_bound=link)`` (the kept tree's), each row's answer kept by the caller.
    sampled : ``sampled(cloud, params)`` gives what :func:`sampled_points` gives (the subsample's rows, its
        index, its tau), kept by the caller (an edit's update: the subsample drawn, its index checked
        and its tau found once per evaluation, 39 ms of CPU a call at 1M points).
    chords : the half chords of earlier calls on the same cloud (:class:`.chord_cache.ChordCache`, the
        evaluation's, shared by its updates): beside a branch marches only the ones not kept.
    checkpoint : ``checkpoint(fraction)``, raises to cancel.

    An empty skeleton explains nothing: one region per connected part of the cloud, depth inf.
    """
    p = params
    cloud = np.asarray(cloud, dtype=float).reshape(-1, 3)
    n = len(cloud)
    checkpoint(0.0)
    n_out = 0
    if inside is not None and keep is not None and not isinstance(skeleton, CurveSkeleton):
        skeleton, keep = np.asarray(skeleton, dtype=float).reshape(-1, 3)[np.asarray(keep, dtype=bool)], None
    if inside is not None and cov is not None:  # the evaluation's coverage holds while every element is inside
        tau = float(cov.tau)
        if not coverage_holds(cloud, skeleton, cov, p, inside):
            cov = None
    sub: np.ndarray | None = None
    spread_factor = 1.0
    full_covered = None
    if cov is not None:
        if len(cov.covered) != n:
            raise ValueError(f"coverage has {len(cov.covered)} cloud points, the cloud {n}")
        pts = cloud
        tau = float(cov.tau)
        if cov.sample_rows is not None:  # estimated coverage: the regions on its sample, then spread
            sub = cov.sample_rows
            pts = cloud[sub]
            full_covered = cov.covered
            cov = replace(cov, gap=cov.gap[sub], covered=cov.covered[sub], sample_rows=None)
            spread_factor = float(np.sqrt(n / len(pts)))
    else:
        sub, index, index_tau = (sampled or sampled_points)(cloud, p)
        pts = index.cloud  # the same bits; the same array at every update (coverage keeps its noise sample)
        if sub is not None:  # the spacing of a surface sample grows as 1 / sqrt(density)
            tau = None if tau is None else float(tau) * float(np.sqrt(n / len(pts)))
        if tau is None:
            tau = index_tau(lambda f: checkpoint(0.1 * f))
    # the regions link sampled neighbours: the spacing of a surface sample grows as 1 / sqrt(density)
    spacing = float(tau) / float(p.coverage_tau_factor) * spread_factor
    if keep is not None and not isinstance(skeleton, CurveSkeleton):
        skeleton = np.asarray(skeleton, dtype=float).reshape(-1, 3)[np.asarray(keep, dtype=bool)]
    cov_elements = None
    if cov is None:
        elements, n_out = coverage_elements(skeleton, pts, spacing, p, inside, lambda f: checkpoint(0.1))
        cov_elements = elements
        if coverage_of is not None:
            cov = coverage_of(pts, elements, float(tau), index)
        else:
            cov = coverage(pts, elements, p, tau, checkpoint=lambda f: checkpoint(0.1 + 0.6 * f), index=index)
    checkpoint(0.7)
    # not for an estimated coverage's sample: a new array each time
    kept_tree = None if cloud_tree is None or full_covered is not None else (lambda: cloud_tree(pts))
    region_s, regions = _regions(pts, cov, spacing, p, checkpoint, tree=kept_tree,
                                 neighbours=None if kept_tree is None else neighbours,
                                 small=lambda tree: _small_points(skeleton, tree, spacing, p))
    checkpoint(0.9)
    explained_s = cov.covered
    if sub is not None:
        nearest = None if nearest_sample is None or full_covered is not None else nearest_sample
        region, explained = _spread(cloud, pts, region_s, explained_s, spacing,
                                    lambda f: checkpoint(0.9 + 0.1 * f), nearest)
        if full_covered is not None:  # the coverage's own verdicts: completeness = its fraction
            explained = full_covered
            region[explained] = -1
    else:
        region, explained = region_s, explained_s
    counts = np.bincount(region[region >= 0], minlength=len(regions))
    out: list[MissingRegion] = []
    for k, r in enumerate(regions):
        share = float(counts[k]) / n
        out.append(MissingRegion(
            id=k, n_points=int(counts[k]), share=share, depth=r["depth"], reach=r["reach"],
            border_radius=r["border_radius"], centroid=np.asarray(to_user(r["centroid"][None]))[0],
            deepest=int(r["deepest"] if sub is None else sub[r["deepest"]]),
            counted=bool(r["depth"] >= (p.missing_depth if share >= p.missing_min_share else p.missing_small_depth)
                         or share >= p.missing_large_share),  # NaN: not measured
        ))  # fmt: skip
    completeness = float(explained.mean()) if n else 1.0
    if any(r.counted for r in out) or completeness < float(p.missing_min_completeness):
        if cov_elements is None:
            cov_elements = skeleton_elements(skeleton, spacing, int(p.missing_max_elements))
        tree = kept_tree() if kept_tree is not None else cKDTree(pts)
        _mark_beside(out, pts, tree, region_s, cov_elements, spacing, p, completeness, chords)
    checkpoint(1.0)
    return MissingParts(
        outside_elements=n_out,
        completeness=completeness,
        explained=explained,
        region=region.astype(np.int32),
        regions=out,
        n_elements=int(cov.n_elements),
        subsample=None if sub is None else int(len(sub)),
        what=what,
        thresholds={"missing_depth": float(p.missing_depth), "missing_min_share": float(p.missing_min_share),
                    "missing_min_area": float(p.missing_min_area),
                    "missing_small_depth": float(p.missing_small_depth),
                    "missing_large_share": float(p.missing_large_share),
                    "missing_min_completeness": float(p.missing_min_completeness)},
    )


def _mark_beside(regions: list[MissingRegion], pts: np.ndarray, tree: cKDTree, region: np.ndarray,
                 elements: np.ndarray, spacing: float, p: Params, completeness: float,
                 chords: ChordCache | None = None) -> None:
    """Mark the regions beside a branch (:func:`.beside.beside_regions`) and uncount them: the counted ones,
    and while the completeness is under ``missing_min_completeness`` also the largest others of at least
    ``SMALL_FEWEST`` points (at most ``BESIDE_REGIONS`` in all; ``region``: each row of ``pts``' region)."""
    ask = [r for r in regions if r.counted]
    if completeness < float(p.missing_min_completeness):
        ask += [r for r in regions if not r.counted and r.n_points >= SMALL_FEWEST]
    ask = ask[:BESIDE_REGIONS]
    if not ask:
        return
    found = beside_regions(pts, tree, region, np.array([r.id for r in ask]), elements, spacing,
                           float(p.missing_beside_quantile), float(p.missing_beside_radii),
                           float(p.missing_beside_end_radii), float(p.missing_beside_beyond), chords)
    for r, b in zip(ask, found):
        if b:
            r.beside, r.counted = True, False


def coverage_holds(cloud: np.ndarray, skeleton: np.ndarray | CurveSkeleton, cov: Coverage, p: Params,
                   inside: Callable[[np.ndarray], np.ndarray] | None) -> bool:
    """Whether :func:`missing_parts` takes the evaluation's coverage ``cov`` of ``skeleton`` as it is:
    no ``inside`` test, or no element in the air (:func:`_in_air`; else the coverage is computed again
    without those elements)."""
    if inside is None:
        return True
    elements = skeleton_elements(skeleton, float(cov.tau) / float(p.coverage_tau_factor), int(p.missing_max_elements))
    return not (len(elements) and _in_air(elements, inside, np.asarray(cloud, dtype=float).reshape(-1, 3), p).any())


def explained_alone(cloud: np.ndarray, skeleton: np.ndarray | CurveSkeleton, cov: Coverage, p: Params,
                    inside: Callable[[np.ndarray], np.ndarray] | None) -> np.ndarray | None:
    """The verdict per cloud point :func:`missing_parts` gives (``MissingParts.explained``) from the
    coverage ``cov``, without finding the regions: ``cov``'s own (on the whole cloud also when it was
    estimated on a sample). None when :func:`missing_parts` would not take ``cov`` as it is
    (:func:`coverage_holds`) or would refuse it."""
    covered = np.asarray(cov.covered, bool)
    if len(covered) != len(np.asarray(cloud).reshape(-1, 3)) or not coverage_holds(cloud, skeleton, cov, p, inside):
        return None
    return covered


def completeness_alone(cloud: np.ndarray, skeleton: np.ndarray | CurveSkeleton, cov: Coverage, p: Params,
                       inside: Callable[[np.ndarray], np.ndarray] | None) -> float | None:
    """The completeness :func:`missing_parts` gives from the coverage ``cov`` (the share of the cloud
    :func:`explained_alone` finds explained): a repair's first look reads it alone (docs/repair.md
    "The repair's cost"). None when :func:`explained_alone` is."""
    explained = explained_alone(cloud, skeleton, cov, p, inside)
    if explained is None:
        return None
    return float(explained.mean()) if len(explained) else 1.0


def sampled_points(cloud: np.ndarray, p: Params
                   ) -> tuple[np.ndarray | None, CloudIndex, Callable[[Checkpoint], float]]:
    """The points the regions are found on: (their cloud rows, None for all; their index; their tau,
    ``coverage_tau`` of them, when called): above ``missing_max_points`` a random subsample of that
    many, the same at every call (``SUBSAMPLE_SEED``); the index kept while the same points come back
    (:func:`kept_index`: an edit's update asks again about the same points)."""
    n = len(cloud)
    sub = None
    if n > int(p.missing_max_points):
        sub = np.sort(np.random.default_rng(SUBSAMPLE_SEED).choice(n, int(p.missing_max_points), replace=False))
    index = kept_index(cloud if sub is None else cloud[sub], cloud)
    return sub, index, lambda checkpoint: coverage_tau(index.cloud, p, checkpoint, index)


def _spread(cloud: np.ndarray, pts: np.ndarray, region_s: np.ndarray, explained_s: np.ndarray,
            spacing: float, checkpoint: Checkpoint = no_checkpoint,
            nearest: Callable[[np.ndarray, np.ndarray, Checkpoint], tuple[np.ndarray, np.ndarray]] | None = None,
            ) -> tuple[np.ndarray, np.ndarray]:
    """Every cloud point takes the verdict of its nearest sample ``pts``; only points within
    ``SPREAD`` spacings of an unexplained sample are looked up (the rest are explained: a point
    farther than that from every sample, its nearest one included, is no sample's neighbour).
    ``SPREAD_CHUNK`` cloud rows at a time, a checkpoint between (one 1M-row query held a cancel).
    With ``nearest`` (each cloud point's nearest sample, kept): see :func:`_spread_kept`."""
    region = np.full(len(cloud), -1, np.int64)
    explained = np.ones(len(cloud), bool)
    un = np.flatnonzero(~explained_s)
    if len(un) == 0:
        return region, explained
    if nearest is not None:
        return _spread_kept(cloud, pts, region_s, explained_s, spacing, nearest(cloud, pts, checkpoint))
    unexplained_tree, sample_tree = cKDTree(pts[un]), None
    for lo in range(0, len(cloud), SPREAD_CHUNK):
        checkpoint(lo / len(cloud))
        part = cloud[lo:lo + SPREAD_CHUNK]
        d, _ = unexplained_tree.query(part, distance_upper_bound=SPREAD * spacing, workers=query_workers(len(part)))
        near = np.flatnonzero(np.isfinite(d))
        if len(near):
            sample_tree = cKDTree(pts) if sample_tree is None else sample_tree
            j = sample_tree.query(part[near], workers=query_workers(len(near)))[1]
            region[lo + near], explained[lo + near] = region_s[j], explained_s[j]
    return region, explained


def _spread_kept(cloud: np.ndarray, pts: np.ndarray, region_s: np.ndarray, explained_s: np.ndarray,
                 spacing: float, near: tuple[np.ndarray, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_spread` from each cloud point's nearest sample ``near`` (distance, row): a point whose
    nearest sample is explained takes the default (explained, no region) either way; one whose nearest
    is unexplained has it as its nearest unexplained sample too, so it is looked up when that distance
    is under ``SPREAD`` spacings (the search's strict test on squared distances: the few within a
    relative 1e-9 of the bound are asked of the unexplained samples' tree as there)."""
    d, j = near
    bound = SPREAD * spacing
    un = ~explained_s[j]
    near_un = un & (d < bound * (1 - 1e-9))
    edge = np.flatnonzero(un & ~near_un & (d <= bound * (1 + 1e-9)))
    if len(edge):
        tree = cKDTree(pts[np.flatnonzero(~explained_s)])
        near_un[edge] = np.isfinite(tree.query(cloud[edge], distance_upper_bound=bound)[0])
    rows = np.flatnonzero(near_un)
    region = np.full(len(cloud), -1, np.int64)
    explained = np.ones(len(cloud), bool)
    region[rows], explained[rows] = region_s[j[rows]], explained_s[j[rows]]
    return region, explained


def _in_air(elements: np.ndarray, inside: Callable[[np.ndarray], np.ndarray], pts: np.ndarray,
            p: Params) -> np.ndarray:
    """The elements whose balls explain nothing: ``inside`` rejects them and either their ball (their
    distance to the cloud) is over ``missing_air_ball`` x the median ball of the elements it accepts
    (an edge through the air crosses gaps far wider than the shape), or they face the shape from
    outside: the point one median ball beyond their nearest cloud point, away from them, is inside
    (a chord across a torus's hole sees the ring's solid behind its inner side). The axis of a tube
    seen from one side lies in no solid voxel, keeps the tube's radius and sees air behind the
    cloud. All it rejects when it accepts none."""
    out = ~np.asarray(inside(elements), bool)
    if not out.any() or out.all():
        return out
    r, j = kd_tree(pts).query(elements, workers=query_workers(len(elements)))
    median = float(np.median(r[~out]))
    wide = r > float(p.missing_air_ball) * median
    rows = np.flatnonzero(out & ~wide & (r > 0))
    facing = np.zeros(len(elements), bool)
    if len(rows):
        u = (pts[j[rows]] - elements[rows]) / r[rows, None]
        facing[rows] = np.asarray(inside(pts[j[rows]] + median * u), bool)
    return out & (wide | facing)


def _small_points(skeleton: np.ndarray | CurveSkeleton, tree: cKDTree, spacing: float, p: Params) -> float:
    """The fewest points of a region smaller than ``missing_min_share`` that is measured: the surface
    of ``missing_min_area`` squared median ball radii (a point stands for a spacing squared), so the
    same part of the shape at any density (inf without elements or spacing)."""
    elements = skeleton_elements(skeleton, spacing, int(p.missing_max_elements))
    if not len(elements) or not spacing > 0 or tree.n == 0:
        return np.inf
    step = max(1, len(elements) // SMALL_ELEMENTS)  # a median needs no more
    r = float(np.median(_element_distances(tree, elements, step)))
    return max(float(p.missing_min_area) * r * r / (spacing * spacing), 1.0)


def _element_distances(tree: cKDTree, elements: np.ndarray, step: int) -> np.ndarray:
    """``tree.query(elements[::step])``'s distances. The answers of the last element sets asked of
    ``tree`` are kept (``_SMALL_KEPT``): an element with the bits of one asked before (a hash of its
    bytes, its bits compared) takes its distance, the tree's for the same point; the first time a tree
    is asked with a step of at most ``_SMALL_EVERY``, every element is asked, so that the next curves'
    subsamples (an edit shifts which elements a step picks) find theirs (docs/repair.md "The repair's
    own costs cut")."""
    sub = elements[::step]
    with _SMALL_LOCK:
        kept = next((k for k in _SMALL_KEPT if k[0] is tree), None)
    if kept is None and step <= _SMALL_EVERY:
        every = np.ascontiguousarray(elements, dtype=float)
        d_all = tree.query(every, workers=query_workers(len(every)))[0]
        _keep_distances(tree, every, d_all, None)
        return d_all[::step]
    d = np.zeros(len(sub))
    miss = np.ones(len(sub), bool)
    if kept is not None:
        key, words = row_hash(sub), row_words(sub)
        _, sorted_key, order, kept_words, kept_d = kept
        cand, same = find_rows(sorted_key, order, kept_words, key, words)
        miss = ~same
        d[~miss] = kept_d[cand[~miss]]
    if miss.any():
        ask = np.ascontiguousarray(sub[miss], dtype=float)
        d[miss] = tree.query(ask, workers=query_workers(len(ask)))[0]
        _keep_distances(tree, ask, d[miss], kept)
    return d


def _keep_distances(tree: cKDTree, points: np.ndarray, d: np.ndarray, kept: tuple | None) -> None:
    """Keep ``points``' distances for ``tree``, with ``kept``'s while both hold at most
    ``_SMALL_ROWS`` rows (the oldest tree's dropped beyond ``_SMALL_TREES``)."""
    words, d = row_words(points).copy(), np.asarray(d, float).copy()
    if kept is not None and len(kept[3]) + len(words) <= _SMALL_ROWS:
        words, d = np.vstack([kept[3], words]), np.concatenate([kept[4], d])
    key = row_hash(words.view(np.float64))
    order = np.argsort(key, kind="stable")
    with _SMALL_LOCK:
        _SMALL_KEPT[:] = [k for k in _SMALL_KEPT if k[0] is not tree][-(_SMALL_TREES - 1):]
        _SMALL_KEPT.append((tree, key[order], order, words, d))


def _regions(pts: np.ndarray, cov: Coverage, spacing: float, p: Params, checkpoint: Checkpoint,
             tree: Callable[[], cKDTree] | None = None, small: Callable[[cKDTree], float] | None = None,
             neighbours: Callable[[cKDTree, np.ndarray, int, float], tuple[np.ndarray, np.ndarray]] | None = None,
             ) -> tuple[np.ndarray, list[dict]]:
    """Region id per point (-1 explained; ids by size, largest first) and each region's numbers.

    Border: the region's points with an explained point among their neighbours (within the link).
    Radius at the border: the RMS distance of the largest connected piece of the border from its
    centroid (a ring around a tube: the tube's radius; it is the cross-section's extent, not an
    inscribed ball's, so a flat part a curve crosses is not a missing part). Depth: the region's
    ``missing_depth_quantile`` distance to its border over that radius. Regions under both
    ``missing_min_share`` of the points and ``small(tree)`` points (the area rule; asked only when
    such a region holds ``SMALL_FEWEST`` points) get no depth (NaN): they cannot count. ``tree()``
    gives ``cKDTree(pts)`` when it is kept (built here at most once otherwise), ``neighbours`` its
    searches' answers kept per point (:func:`_from_kept`)."""
    n = len(pts)
    made: list[cKDTree] = []

    def pts_tree() -> cKDTree:
        if not made:
            made.append(cKDTree(pts) if tree is None else tree())
        return made[0]

    region = np.full(n, -1, np.int64)
    miss = np.flatnonzero(~cov.covered)
    if len(miss) == 0:
        return region, []
    up = pts[miss]
    link = float(p.missing_link_factor) * spacing
    k = min(LINK_K + 1, len(miss))
    kk = min(LINK_K + 1, n)
    # with a kept tree, one search of it gives most points' neighbours both ways (_from_kept), read in one
    # compiled pass (region_links: the links and the border it settles)
    kept = None if tree is None or k < 2 else _from_kept(pts_tree(), up, miss, link, neighbours)
    passed = None if kept is None else region_links(*kept, cov.covered, k, kk)
    if k > 1:
        heads, tails = _unexplained_links(up, k, link, passed, None if kept is None else (pts_tree(), miss))
    else:
        heads, tails = np.empty(0, np.int64), np.empty(0, np.int64)
    # the links as edges: scipy's undirected labels by a union-find, whatever their order (docs/performance.md 6.10)
    n_comp, label = undirected_components(len(miss), heads, tails)
    checkpoint(0.75)
    size = np.bincount(label, minlength=n_comp)
    rank = np.empty(n_comp, np.int64)
    rank[np.lexsort((np.arange(n_comp), -size))] = np.arange(n_comp)
    label = rank[label]
    size = np.bincount(label, minlength=n_comp)
    region[miss] = label
    # one coordinate at a time: the same sums in the same order as np.add.at (6 x faster)
    sums = np.stack([np.bincount(label, weights=up[:, c], minlength=n_comp) for c in range(3)], axis=1)
    centroid = sums / size[:, None]
    floor = max(1.0, float(p.missing_min_share) * n)
    if small is not None and np.any((size < floor) & (size >= SMALL_FEWEST)):
        floor = min(floor, max(float(SMALL_FEWEST), small(pts_tree())))
    big = np.flatnonzero(size >= floor)
    depth = np.full(n_comp, np.nan)
    reach = np.full(n_comp, np.nan)
    radius = np.full(n_comp, np.nan)
    if len(big):
        # border points of the big regions: an explained cloud point among their neighbours
        in_big = np.isin(label, big)
        q = np.flatnonzero(in_big)
        border = np.zeros(len(miss), bool)
        border[q] = _border(pts_tree(), up, q, kk, link, passed, cov.covered)
        # pieces of the border (the two rings of an arc cut out of a loop): border points closer than
        # BORDER_LINK links are one piece (the border of a scan's region is sparse and ragged)
        bi = np.flatnonzero(border)
        piece = np.zeros(len(miss), np.int64)
        if len(bi) > 1:
            pairs = cKDTree(up[bi]).query_pairs(BORDER_LINK * link, output_type="ndarray")
            piece[bi] = undirected_components(len(bi), pairs[:, 0], pairs[:, 1])[1]
        for c in big:
            checkpoint(0.75 + 0.15 * float(c) / max(1, n_comp))
            members = np.flatnonzero(label == c)
            b = members[border[members]]
            if len(b) == 0:  # nothing of the skeleton's reach touches it: all of it is missing
                depth[c], reach[c], radius[c] = np.inf, np.inf, np.nan
                continue
            pid, cnt = np.unique(piece[b], return_counts=True)
            main = b[piece[b] == pid[np.argmax(cnt)]]
            ring = up[main]
            rho = float(np.sqrt(np.mean(np.sum((ring - ring.mean(axis=0)) ** 2, axis=1))))
            rho = max(rho, spacing)
            r_q = _quantile_distance(up[b], up[members], float(p.missing_depth_quantile))
            depth[c], reach[c], radius[c] = r_q / rho, r_q, rho
    deepest = miss[_last_largest(cov.gap[miss], label, n_comp)]  # each region's point farthest from the balls
    out = [{"depth": float(depth[c]), "reach": float(reach[c]), "border_radius": float(radius[c]),
            "centroid": centroid[c], "deepest": int(deepest[c])} for c in range(n_comp)]
    return region, out


def _quantile_distance(border: np.ndarray, pts: np.ndarray, q: float) -> float:
    """``np.quantile`` of each point's distance to its nearest ``border`` point (``cKDTree(border).query``),
    the same bits, searched only for the points whose distance may hold the quantile's order statistics:
    each distance lies within the reach of ``QUANTILE_CENTRES`` of the border points (each border point's
    distance to the nearest of them) below its distance to the nearest of them; the points surely below
    (above) those statistics enter as -inf (inf), which moves no statistic between them. A region of
    30k points whose border is a ring of 189 took 18 ms of CPU searched whole."""
    n = len(pts)
    if n < QUANTILE_FEWEST or len(border) < 2 * QUANTILE_CENTRES:
        return float(np.quantile(_border_distance(border, pts), q))
    centres = border[:: len(border) // QUANTILE_CENTRES]
    to_c = np.sqrt(nearest_squared(pts, centres))
    reach = float(np.sqrt(nearest_squared(border, centres).max())) * (1 + 1e-9)
    upper = to_c * (1 + 1e-9)  # a relative 1e-9 for the rounding of either search
    lower = to_c * (1 - 1e-9) - reach
    h = int(np.floor((n - 1) * q))
    k0, k1 = max(h - 1, 0), min(h + 2, n - 1)  # the ranks np.quantile reads, and one more each side
    below = upper < np.partition(lower, k0)[k0]
    above = lower > np.partition(upper, k1)[k1]
    ask = np.flatnonzero(~below & ~above)
    dist = np.where(below, -np.inf, np.inf)
    dist[ask] = _border_distance(border, pts[ask])
    return float(np.quantile(dist, q))


def _border_distance(border: np.ndarray, pts: np.ndarray) -> np.ndarray:
    """``cKDTree(border).query(pts)[0]``, the same bits: up to ``BORDER_PAIRS`` pairs the square root of
    each point's least ``(dx^2 + dy^2) + dz^2`` over the border (scipy's squared distance, summed in that
    order, its root taken last; :func:`skelcore.metrics.point_passes.nearest_squared`), else the tree's.
    A far point sees a ring of border points all about as near, and the tree visits most of them: the
    prune's 3,345 points asked of a ring of 189, 3.3 -> 1.0 ms (docs/performance.md 6.10)."""
    if len(pts) * len(border) <= BORDER_PAIRS:
        return np.sqrt(nearest_squared(pts, border))
    return cKDTree(border).query(pts, workers=query_workers(len(pts)))[0]


def _last_largest(values: np.ndarray, label: np.ndarray, n_labels: int) -> np.ndarray:
    """Per label 0 .. n_labels - 1 (each present), the last row of its largest value: the last of
    each label in ``np.lexsort((values, label))`` order, without sorting (a region's 30k gaps: 3.9 ->
    0.3 ms); sorted as that when some value is NaN."""
    if np.isnan(values).any():
        order = np.lexsort((values, label))
        out = np.zeros(n_labels, np.int64)
        out[label[order]] = order
        return out
    top = np.full(n_labels, -np.inf)
    np.maximum.at(top, label, values)
    rows = np.flatnonzero(values == top[label])
    out = np.zeros(n_labels, np.int64)
    np.maximum.at(out, label[rows], rows)
    return out


def _from_kept(tree: cKDTree, up: np.ndarray, miss: np.ndarray, link: float,
               neighbours: Callable[[cKDTree, np.ndarray, int, float], tuple[np.ndarray, np.ndarray]] | None = None,
               ) -> tuple[np.ndarray, ...]:
    """The ``LINK_K + 2`` nearest cloud points within the link of each unexplained point ``up``
    (rows ``miss`` of the cloud) from the cloud's tree (or its answers kept, ``neighbours``, read in
    place): (a table of distances, of cloud rows (int32, n where none), each unexplained point's row of
    the table, each cloud row's unexplained row or -1 (n + 1 entries)), as :func:`region_links` reads them."""
    n = tree.n
    if neighbours is not None:
        d, j = neighbours(tree, miss, min(LINK_K + 2, n), link)
        rows = miss
    else:
        d, j = tree.query(up, k=min(LINK_K + 2, n), distance_upper_bound=link, workers=query_workers(len(up)))
        rows = np.arange(len(up))
    d, j = d.reshape(len(d), -1), np.asarray(j, np.int32).reshape(len(d), -1)
    at = np.full(n + 1, -1, np.int32)
    at[miss] = np.arange(len(miss))
    return d, j, rows, at


def _unique_first(d: np.ndarray, c: int) -> np.ndarray:
    """Rows whose first ``c`` neighbours are the only ``c`` nearest (any search finds the same):
    fewer found within the link, or the next strictly farther."""
    if d.shape[1] <= c:
        return np.ones(len(d), bool)
    return ~np.isfinite(d[:, c - 1]) | (d[:, c] > d[:, c - 1])


def _edges(d: np.ndarray, j: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The links of the unexplained points ``rows`` from their ``k`` nearest (distances ``d``, rows ``j``,
    themselves first): each row to every other one found within the link."""
    d, j = d.reshape(len(rows), -1), j.reshape(len(rows), -1)
    ok = np.isfinite(d[:, 1:])
    return np.repeat(np.asarray(rows, np.int64), ok.sum(axis=1)), np.asarray(j[:, 1:][ok], np.int64)


def _unexplained_links(up: np.ndarray, k: int, link: float, passed: tuple | None,
                       cloud: tuple[cKDTree, np.ndarray] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Each unexplained point's links (heads, tails) to its ``k - 1`` nearest other unexplained points within
    the link, the sets ``cKDTree(up).query(k=k)`` gives (equally near ones may come in another order): from
    ``passed`` (:func:`region_links` of the kept answers) where its ``k`` nearest cloud points are the only
    ones, all unexplained and none as near as the point itself; the others from :func:`_near_rows` when the
    cloud's tree and the unexplained rows ``cloud`` are given, else searched."""
    if passed is None:
        d, j = cKDTree(up).query(up, k=k, distance_upper_bound=link, workers=query_workers(len(up)))
        return _edges(d, j, np.arange(len(up)))
    heads, tails = [passed[0]], [passed[1]]
    redo = np.flatnonzero(passed[2])
    if len(redo) and cloud is not None and len(redo) <= NEAR_ROWS_SHARE * len(up):
        d, j, left = _near_rows(up, redo, k, link, *cloud)
        h, t = _edges(d[~left], j[~left], redo[~left])
        heads.append(h)
        tails.append(t)
        redo = redo[left]
    if len(redo):
        d, j = cKDTree(up).query(up[redo], k=k, distance_upper_bound=link, workers=query_workers(len(redo)))
        h, t = _edges(d, j, redo)
        heads.append(h)
        tails.append(t)
    return np.concatenate(heads), np.concatenate(tails)


def _near_rows(up: np.ndarray, rows: np.ndarray, k: int, link: float, tree: cKDTree,
               miss: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``cKDTree(up).query(up[rows], k, distance_upper_bound=link)`` from a tree of the unexplained
    points within the link of ``rows`` alone (found in the cloud's ``tree``, ``up`` = its rows
    ``miss``): every point a row can find is in it, so where a row's ``k``-th is the only one as near
    (:func:`_unique_first`) and no other point as near as itself, its set is the whole tree's; the
    rows where not (ties), True in the third array, are left to the caller. A tree of all ``up`` for a
    few rows took most of the regions' search after a pruned arm (30k points for 189 rows at 100k)."""
    at = np.full(tree.n, -1, np.int64)
    at[miss] = np.arange(len(miss))
    hits = tree.query_ball_point(up[rows], link * (1 + 1e-9), return_sorted=False)
    near = at[np.concatenate([np.asarray(h, np.int64) for h in hits])] if len(hits) else np.zeros(0, np.int64)
    near = np.unique(near[near >= 0])  # the rows themselves among them
    dd, jj = cKDTree(up[near]).query(up[rows], k=k + 1, distance_upper_bound=link)
    dd, jj = dd.reshape(len(rows), -1), jj.reshape(len(rows), -1)
    jj = np.where(np.isfinite(dd), np.concatenate([near, [len(up)]])[np.minimum(jj, len(near))], len(up))
    left = ~_unique_first(dd, k)
    if k > 1:
        left |= ~(dd[:, 1] > 0)
    return dd[:, :k], jj[:, :k], left


def _border(tree: cKDTree, up: np.ndarray, q: np.ndarray, kk: int, link: float, passed: tuple | None,
            covered: np.ndarray) -> np.ndarray:
    """Whether an explained cloud point is among the ``kk`` nearest cloud points within the link of each
    unexplained point ``up[q]``: from ``passed`` (:func:`region_links`) where they are the only ``kk``
    nearest, else searched."""
    if passed is None:
        out, redo = np.zeros(len(q), bool), np.arange(len(q))
    else:
        out, redo = passed[3][q], np.flatnonzero(passed[4][q])
    if len(redo):
        dd, j = tree.query(up[q[redo]], k=kk, distance_upper_bound=link, workers=query_workers(len(redo)))
        dd, j = dd.reshape(len(redo), -1), j.reshape(len(redo), -1)
        explained = np.concatenate([covered, [False]])
        out[redo] = explained[np.where(np.isfinite(dd), j, tree.n)].any(axis=1)
    return out
