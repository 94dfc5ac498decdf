"""Coverage: how much of the cloud a skeleton's medial balls reconstruct (SkelScope's own, not the
paper's; docs/metrics.md 5.2).

Each skeleton element x (skeletal point, curve sample) gets the radius r(x) = distance to its
nearest cloud point, its inscribed ball. A cloud point p has the gap g(p) = min_x |p - x| - r(x)
(>= 0: its distance to the union of the balls); ``mean_gap`` and ``max_gap`` (one-sided Hausdorff
distance from the cloud to the balls) summarise it. p is covered when min_x |p - x| - (1 + s) r(x)
<= tau (``Params.coverage_slack`` s, tau = ``coverage_tau_factor`` x median NN spacing; r(x) plus the
noise shortfall of :func:`noise_shortfall`, ``coverage_radius_quantile``): a curve's
balls never fill a shape's ends, so a complete skeleton must not need them to.  All three searches
are exact, in the compiled kernel ``_balls.c`` (:mod:`.ball_tree`) on every core, a checkpoint every ~0.1 s.  Above
``Params.coverage_exact_points`` cloud points the gaps are found for a random subsample of the cloud
and of the elements only (radii still from the whole cloud), the other points taking their nearest
sampled point's answer (``Coverage.subsample``; docs/metrics.md 5.2, docs/performance.md 6.6).
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from ..correspondence import densify_curve
from ..curve import CurveSkeleton
from ..geometry import Checkpoint, kd_tree, no_checkpoint, scaled_checkpoint, unique_rows
from ..params import Params
from .ball_tree import BallTree
from .cloud_index import CloudIndex

__all__ = ["Coverage", "coverage", "coverage_tau", "curve_elements", "min_ball_excess", "covered_by_balls", "BallTree",
           "noise_shortfall"]

# the random subsample above coverage_exact_points (the same seed as the diagnostics' subsamples)
SAMPLE_SEED = 0
# the noise shortfall of the radii (noise_shortfall): cloud points it reads, a cell's fewest territory
# points, cell side in sample spacings, the shortfall (in r(x)) below which a cloud counts as clean
NOISE_SAMPLE = 20_000
NOISE_MIN_POINTS = 8
NOISE_CELL = 4.0
NOISE_DEAD = 0.1
# a cell's territory is a shell when its excess spreads (between the quantile q and 1 - q) over at most
# this many x its radius (Gaussian noise of 0.25 r at 20k points: about 1.4)
NOISE_SPREAD = 2.0


@dataclass
class Coverage:
    """Per cloud point ``gap`` and ``covered``; ``fraction``, ``mean_gap``, ``max_gap`` (normalized).
    ``subsample``: None when exact, else how many cloud points were asked (``sample_rows``, sorted)
    while the others took their nearest sampled point's values."""

    gap: np.ndarray
    covered: np.ndarray
    fraction: float
    mean_gap: float
    max_gap: float
    tau: float
    slack: float
    n_elements: int
    subsample: int | None = None
    sample_rows: np.ndarray | None = None

    def to_dict(self) -> dict:
        out = {"fraction": self.fraction, "mean_gap": self.mean_gap, "max_gap": self.max_gap}
        if self.subsample is not None:
            out["subsample"] = self.subsample
        return out


def coverage_tau(cloud: np.ndarray, params: Params = Params(), checkpoint: Checkpoint = no_checkpoint,
                 index: CloudIndex | None = None) -> float:
    """tau = coverage_tau_factor x the cloud's median nearest-neighbour spacing (0 for a copy; the
    values of ``geometry.nearest_neighbor_distances``, from the kernel's tree); with ``index`` (the
    cloud's :class:`.cloud_index.CloudIndex`) from its shared spacings, the same value."""
    if index is not None:
        return float(params.coverage_tau_factor * index.median_spacing(checkpoint))
    cloud = np.asarray(cloud, dtype=float).reshape(-1, 3)
    if len(cloud) < 2:
        return 0.0
    tree = BallTree(cloud, checkpoint=scaled_checkpoint(checkpoint, 0.0, 0.3))
    d = tree.nearest(tree.points, scaled_checkpoint(checkpoint, 0.3, 1.0), others=True)
    return float(params.coverage_tau_factor * np.median(d))



def curve_elements(curve: CurveSkeleton, tau: float, params: Params) -> np.ndarray:
    """A curve's coverage elements: the curve densified to tau / ``coverage_tau_factor`` (at most 200k
    pieces) plus its vertices (docs/metrics.md section 5.2)."""
    step = max(tau / params.coverage_tau_factor, float(curve.edge_lengths().sum()) / 200_000)
    pts, _ = densify_curve(curve, step)
    return np.vstack([pts, curve.vertices])

def min_ball_excess(
    points: np.ndarray, centers: np.ndarray, radii: np.ndarray, floor: float = -np.inf,
    checkpoint: Checkpoint = no_checkpoint, workers: int | None = None,
) -> np.ndarray:
    """Min over balls of |p - c| - radius for every point p (negative inside a ball), exact where
    it exceeds ``floor`` (elsewhere some value <= floor: enough to clip or threshold at floor);
    inf without balls.  Points are asked in the order of their own tree (neighbours' answers seed)."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    radii = np.ascontiguousarray(radii, dtype=float)
    checkpoint(0.0)
    if len(centers) == 0:
        return np.full(len(points), np.inf)
    tree = BallTree(centers, checkpoint=checkpoint)
    r = radii[tree.perm]
    tree.set_radii(r, r)
    order = BallTree(points, checkpoint=checkpoint).perm
    gap, _ = tree.balls(points[order], cover=False, floor=floor, checkpoint=checkpoint, workers=workers)
    out = np.empty(len(points))
    out[order] = gap
    return out


def covered_by_balls(
    points: np.ndarray, centers: np.ndarray, radii: np.ndarray, checkpoint: Checkpoint = no_checkpoint,
    workers: int | None = None,
) -> np.ndarray:
    """Is each point inside some ball: |p - c|^2 - radius^2 <= 1e-12 x the largest radius^2 (the
    rounding allowance), exact; the first ball found inside ends a point's search."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    checkpoint(0.0)
    if len(centers) == 0:
        return np.zeros(len(points), dtype=bool)
    tree = BallTree(centers, checkpoint=checkpoint)
    r = np.ascontiguousarray(radii, dtype=float)[tree.perm]
    tree.set_radii(r, r)
    order = BallTree(points, checkpoint=checkpoint).perm
    _, inside = tree.balls(points[order], gap=False, checkpoint=checkpoint, workers=workers)
    out = np.empty(len(points), bool)
    out[order] = inside
    return out


def coverage(
    cloud: np.ndarray, elements: np.ndarray, params: Params = Params(), tau: float | None = None,
    checkpoint: Checkpoint = no_checkpoint, workers: int | None = None, index: CloudIndex | None = None,
) -> Coverage:
    """Coverage of the (normalized) cloud by the medial balls of the (normalized) skeleton elements.

    The cloud's tree gives r(x) (elements asked in their tree's order) and the order in which the
    cloud points ask the elements' tree for gap and cover together.  Every tree build and every
    ~0.1 s of queries checks ``checkpoint`` (cancel).  ``index``: the cloud's shared search structures
    (:class:`.cloud_index.CloudIndex` of this ``cloud``), the same values without building them again."""
    cloud = np.asarray(cloud, dtype=float)
    elements = unique_rows(np.asarray(elements, dtype=float), checkpoint)[0]  # as np.unique(axis=0), 10 x faster
    checkpoint(0.0)
    if tau is None:
        tau = coverage_tau(cloud, params, scaled_checkpoint(checkpoint, 0.0, 0.05), index)
    tau = float(tau)
    s = float(params.coverage_slack)
    m = int(params.coverage_exact_points)
    if len(elements) == 0:
        gap, covered = np.full(len(cloud), np.inf), np.zeros(len(cloud), bool)
    elif len(cloud) > m:
        return _estimated(cloud, elements, m, tau, s, checkpoint, workers, index, params)
    else:
        build = scaled_checkpoint(checkpoint, 0.05, 0.1)
        surface = BallTree(cloud, slab=True, checkpoint=build) if index is None else index.surface(build)
        balls = BallTree(elements, checkpoint=build)
        r, contact, rim = _radii(surface, balls, cloud, params, scaled_checkpoint(checkpoint, 0.1, 0.35), workers)
        # |p - x| - (1 + s) r <= tau  <=>  p lies in the ball of radius (1 + s) r + tau
        balls.set_radii(r, (1.0 + s) * r + tau, rim, scaled_checkpoint(checkpoint, 0.35, 0.4), workers)
        # a cloud point that is some element's nearest has excess at most 0 for that ball (exactly 0
        # without a noise shortfall: the same arithmetic both ways) and lies in its larger ball: gap 0,
        # covered, no search
        rest = np.ones(len(cloud), bool)
        rest[contact] = False
        g, c = balls.balls(surface.points[rest], floor=0.0, checkpoint=scaled_checkpoint(checkpoint, 0.4, 1.0), workers=workers,
                           blocks=None)
        gap, covered = np.zeros(len(cloud)), np.ones(len(cloud), bool)
        gap[surface.perm[rest]] = np.maximum(g, 0.0)
        covered[surface.perm[rest]] = c
    return _summary(gap, covered, tau, s, len(elements))


def noise_shortfall(cloud: np.ndarray, elements: np.ndarray, r: np.ndarray, quantile: float,
                    checkpoint: Checkpoint = no_checkpoint,
                    nearest: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """How much noise shrinks each element's radius r(x) (its nearest cloud point's distance), >= 0.

    The nearest of many noisy points lies well inside the true surface: on a tube with Gaussian noise
    of 0.25 r, r(x) is 0.36-0.50 r at 20k points and falls as the cloud grows, so the balls explain
    less and less of a clean axis.  The cloud points nearest to an element (its territory) lie around
    its true radius: per cell of elements (``NOISE_CELL`` sample spacings; the cloud read on a sample of
    at most ``NOISE_SAMPLE``) the ``quantile`` of their excess |p - x| - r(x), over the cell's median
    r(x); the median over the cells whose excess spreads like a shell's (``NOISE_SPREAD``; a missing
    part's end cell spreads over its length), times r(x), when above ``NOISE_DEAD`` (clean clouds keep
    r(x) exactly).  A low quantile: a flat part's territory starts at its narrow side (excess about 0).
    ``nearest``: each sampled point's (distance, row) of its nearest element, as computed here, when
    known (an edited curve's, skelcore/edit/coverage_update.py)."""
    n_el = len(elements)
    out = np.zeros(n_el)
    if not quantile > 0 or n_el == 0 or len(cloud) < 2 * NOISE_MIN_POINTS:
        return out
    pts, spacing = _noise_sample(cloud)
    checkpoint(0.4)
    dist, owner = _nearest_element(elements, pts) if nearest is None else nearest
    excess = np.maximum(dist - r[owner], 0.0)
    cells = np.floor((elements - elements.min(axis=0)) / max(NOISE_CELL * spacing, 1e-12)).astype(np.int64)
    cell = _row_labels(cells)
    group = cell[owner]
    n_cells = int(cell.max()) + 1
    count = np.bincount(group, minlength=n_cells)
    ok = count >= NOISE_MIN_POINTS
    radius, = _group_quantiles(r[owner], group, n_cells, (0.5,))
    ok &= radius > 0
    if not ok.any():
        return out
    # one figure for the cloud: the median over the cells of the shortfall in units of their radius,
    # over the cells whose territory is a shell (a missing part or the cloud around a stub in the air is
    # an end cell's territory: its excess spreads over lengths, not a noise's width); none when most
    # cells are not
    low, high = _group_quantiles(excess, group, n_cells, (quantile, 1.0 - quantile))
    shell = ok & (high - low <= NOISE_SPREAD * radius)
    if np.count_nonzero(shell) < 0.5 * np.count_nonzero(ok):
        return out
    ratio = float(np.median(low[shell] / radius[shell]))
    checkpoint(1.0)
    return ratio * r if ratio > NOISE_DEAD else out


def _nearest_element(elements: np.ndarray, pts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``cKDTree(elements).query(pts)``: each point's nearest element, its distance and row, from
    ``geometry.kd_tree`` and two neighbours (10 x faster from a torus' surface to 262k axis points:
    1.39 -> 0.14 CPU s); a point whose two nearest tie asks the balanced tree as before, so the
    answers are the same bits."""
    if len(elements) < 2:
        return cKDTree(elements).query(pts)
    d, i = kd_tree(elements).query(pts, k=2)
    dist, owner = d[:, 0].copy(), i[:, 0].copy()
    tie = d[:, 0] == d[:, 1]
    if tie.any():
        dist[tie], owner[tie] = cKDTree(elements).query(pts[tie])
    return dist, owner


def _row_labels(cells: np.ndarray) -> np.ndarray:
    """``np.unique(cells, axis=0, return_inverse=True)[1]`` of rows of non-negative integers: one integer
    key per row, in the rows' lexicographic order (about 20 x faster on 262k rows); rows whose key
    would not fit in 63 bits by ``np.unique`` itself."""
    if len(cells) == 0:
        return np.zeros(0, np.int64)
    span = [int(v) + 1 for v in cells.max(axis=0)]
    if cells.min() < 0 or span[0] * span[1] * span[2] >= 2**62:
        return np.unique(cells, axis=0, return_inverse=True)[1].reshape(-1)
    key = (cells[:, 0] * span[1] + cells[:, 1]) * span[2] + cells[:, 2]
    return np.unique(key, return_inverse=True)[1].reshape(-1)


def _noise_sample(cloud: np.ndarray) -> tuple[np.ndarray, float]:
    """:func:`noise_shortfall`'s sample of the cloud and its median spacing, kept for the last cloud
    while the same array comes back (an edited curve's coverage reads the same cloud at every update)."""
    hit = _last_noise.get("entry")  # one tuple, replaced whole: coverage stages run side by side
    if hit is not None and hit[0]() is cloud and hit[1] == len(cloud):
        return (cloud if hit[2] is None else hit[2]), hit[3]
    rng = np.random.default_rng(SAMPLE_SEED)
    pts = cloud if len(cloud) <= NOISE_SAMPLE else cloud[np.sort(rng.choice(len(cloud), NOISE_SAMPLE, replace=False))]
    spacing = float(np.median(cKDTree(pts).query(pts, k=2)[0][:, 1]))
    try:
        ref = weakref.ref(cloud, lambda r, kept=_last_noise: kept.pop("entry", None)
                          if kept.get("entry", (None,))[0] is r else None)
    except TypeError:  # not weak-referenceable: no reuse
        return pts, spacing
    _last_noise["entry"] = (ref, len(cloud), None if pts is cloud else pts, spacing)  # never the cloud itself
    return pts, spacing


_last_noise: dict = {}


def _group_quantile(values: np.ndarray, group: np.ndarray, n_groups: int, q: float) -> np.ndarray:
    """The (lower) ``q`` quantile of ``values`` in each group 0 .. n_groups - 1 (0 for an empty one)."""
    order = np.lexsort((values, group))
    count = np.bincount(group, minlength=n_groups)
    start = np.concatenate([[0], np.cumsum(count)[:-1]])
    at = start + np.floor(q * np.maximum(count - 1, 0)).astype(np.int64)
    out = np.zeros(n_groups)
    has = count > 0
    out[has] = values[order][at[has]]
    return out


def _group_quantiles(values: np.ndarray, group: np.ndarray, n_groups: int,
                     qs: tuple[float, ...]) -> list[np.ndarray]:
    """:func:`_group_quantile` of each of ``qs``, from one sort: the values' own, then the groups' in
    it, stable (a radix sort of 16-bit groups), instead of a lexsort per quantile; the values at each
    rank are those of the lexsort (equal values are the same bits among values without a sign bit:
    distances and excesses). 20k sampled points, three quantiles: 7.3 -> 2.0 ms."""
    if n_groups >= 2**15 or np.signbit(values).any():  # a -0.0 might take a 0.0's rank: as before
        return [_group_quantile(values, group, n_groups, q) for q in qs]
    by_value = np.argsort(values)
    order = by_value[np.argsort(group[by_value].astype(np.int16), kind="stable")]
    count = np.bincount(group, minlength=n_groups)
    start = np.concatenate([[0], np.cumsum(count)[:-1]])
    ranked = values[order]
    has = count > 0
    out = []
    for q in qs:
        at = start + np.floor(q * np.maximum(count - 1, 0)).astype(np.int64)
        one = np.zeros(n_groups)
        one[has] = ranked[at[has]]
        out.append(one)
    return out


def _radii(surface: BallTree, balls: BallTree, cloud: np.ndarray, params: Params, checkpoint: Checkpoint,
           workers: int | None) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Each ball's radius in tree order, r(x) plus its noise shortfall; its nearest cloud point's tree
    position; that point when it lies on the ball's rim (None once a shortfall grew some ball)."""
    r, contact = surface.nearest(balls.points, scaled_checkpoint(checkpoint, 0.0, 0.8), workers, return_index=True)
    add = noise_shortfall(cloud, balls.points, r, float(params.coverage_radius_quantile), scaled_checkpoint(checkpoint, 0.8, 1.0))
    if add.any():
        return r + add, contact, None
    return r, contact, surface.points[contact]


def _summary(gap: np.ndarray, covered: np.ndarray, tau: float, s: float, n_elements: int,
             sample_rows: np.ndarray | None = None) -> Coverage:
    return Coverage(
        gap=gap,
        covered=covered,
        fraction=float(covered.mean()),
        mean_gap=float(gap.mean()),
        max_gap=float(gap.max()),
        tau=tau,
        slack=s,
        n_elements=int(n_elements),
        subsample=None if sample_rows is None else int(len(sample_rows)),
        sample_rows=sample_rows,
    )


def _estimated(cloud: np.ndarray, elements: np.ndarray, m: int, tau: float, s: float,
               checkpoint: Checkpoint, workers: int | None, index: CloudIndex | None = None,
               params: Params = Params()) -> Coverage:
    """Coverage above ``coverage_exact_points`` = m cloud points: the gaps of a random subsample of m
    cloud points to the balls of at most m random elements, each radius r(x) still the distance to
    the whole cloud (a sparser cloud would grow every ball); every other cloud point takes the gap and
    verdict of its nearest sampled point.  The same rules as the exact path otherwise."""
    rng = np.random.default_rng(SAMPLE_SEED)
    n = len(cloud)
    sample_rows = np.sort(rng.choice(n, m, replace=False))
    if len(elements) > m:
        elements = elements[np.sort(rng.choice(len(elements), m, replace=False))]
    build = scaled_checkpoint(checkpoint, 0.05, 0.1)
    surface = BallTree(cloud, slab=True, checkpoint=build) if index is None else index.surface(build)
    balls = BallTree(elements, checkpoint=build)
    r, contact, rim = _radii(surface, balls, cloud, params, scaled_checkpoint(checkpoint, 0.1, 0.35), workers)
    balls.set_radii(r, (1.0 + s) * r + tau, rim, scaled_checkpoint(checkpoint, 0.35, 0.4), workers)
    # the sample in the whole cloud's tree order (neighbours ask one after the other)
    in_sample = np.zeros(n, bool)
    in_sample[sample_rows] = True
    at = np.flatnonzero(in_sample[surface.perm])  # tree positions of the sampled points
    rest = np.ones(n, bool)
    rest[contact] = False
    ask = at[rest[at]]
    g, c = balls.balls(surface.points[ask], floor=0.0, checkpoint=scaled_checkpoint(checkpoint, 0.4, 0.8), workers=workers,
                       blocks=None)
    gap_t, cov_t = np.zeros(n), np.ones(n, bool)  # tree order; the sampled positions only are set
    gap_t[ask], cov_t[ask] = np.maximum(g, 0.0), c
    # every cloud point: its nearest sampled point's answer (the sampled ones: their own)
    if index is None:
        near = BallTree(surface.points[at], checkpoint=scaled_checkpoint(checkpoint, 0.8, 0.85))
        _, idx = near.nearest(surface.points, scaled_checkpoint(checkpoint, 0.85, 1.0), workers, return_index=True)
        j = at[near.perm[idx]]
    else:  # the skeletal set's and the curve's coverage share the sample, hence this spread
        j = index.nearest_sampled(at, scaled_checkpoint(checkpoint, 0.8, 1.0))
    gap, covered = np.empty(n), np.empty(n, bool)
    gap[surface.perm], covered[surface.perm] = gap_t[j], cov_t[j]
    return _summary(gap, covered, tau, s, len(elements), sample_rows)
