"""The skeletonizers' constants (``CaoParams`` for method "cao", ``SkeletonizeParams`` for
"skelscope"), the run report and the progress plumbing.

Defaults follow Cao et al.'s toolbox (``GS.m``) where it has one; every field is settable by name
(``replace``) so the CLI, the study and the viewer share one source of truth.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, fields
from typing import Callable

from ..errors import Cancelled

__all__ = ["CaoParams", "SkeletonizeParams", "AxisParams", "SkeletonizeInfo", "Reporter", "Progress"]

Progress = Callable[[float, str], None]

class _Replaceable:
    """``replace(**changes)`` for the frozen parameter dataclasses: unknown names raise ValueError."""

    def replace(self, **changes):
        unknown = sorted(set(changes) - {f.name for f in fields(self)})
        if unknown:
            raise ValueError(f"unknown skeletonize parameter(s): {', '.join(unknown)}")
        return dataclasses.replace(self, **changes)


@dataclass(frozen=True)
class CaoParams(_Replaceable):
    """Constants of ``method="cao"``: the toolbox's defaults (``GS.m``, ``contraction_by_mesh_laplacian.m``,
    ``compute_point_weight.m``, ``eg_skeleton_laplacian_rosa.m``), one field each.

    Attributes
    ----------
    min_neighbors, max_neighbors, neighbor_fraction : k of the kNN behind the one-rings =
        round(neighbor_fraction x N) clamped to [min_neighbors, max_neighbors] (8, 30, 0.012).
    contraction_weight : initial W_L; None = 1 / (5 x mean one-ring edge length) (the toolbox's
        ``compute_init_laplacian_constraint_weight``, conformal type).
    attraction_weight : initial W_H (WC = 1).
    contraction_scale : W_L is multiplied by this each iteration (s_L = 3).
    contraction_weight_max : cap on W_L (2048).
    attraction_weight_max : cap on W_H (10000); W_H = WC x (original / current min one-ring size).
    weight_row_cap : a Laplacian row whose |sum of cotangent weights| exceeds this is scaled down to
        it (10000, ``compute_point_weight_dcp``).
    max_iterations : the iteration count t stops at this (20).
    termination_ratio : stop when the min-one-ring-size ratio decreased by less than this (0.01);
        the iterate that failed the test is discarded, as is one whose bounding box grew on an axis
        beyond ``bbox_growth_limit`` x the original's (1.2).
    sample_radius_factor : ball radius of the farthest sampling = factor x bounding-box diagonal (0.02).
    fan_start : where a closed one-ring starts (it decides the initial W_L and which neighbour
        ``connect_by_inherit_neigh`` meets first): "qhull" (the toolbox's: the first triangle Qhull
        lists around the point, about 0.14 ms of CPU a point), "axis" (the fan triangle the first
        principal axis crosses, no Qhull call) or "auto" (qhull up to ``qhull_fan_max_points``).
    qhull_fan_max_points : the largest cloud "auto" starts fans the toolbox's way (25000: the
        paper's clouds; 3.4 s of CPU at 22k, docs/skeletonize.md departure 2).
    linear_solver : the contraction's sparse SPD solve: "cholmod" (CHOLMOD from cvxopt, MATLAB's
        backslash path), "superlu" (SciPy) or "auto" (cholmod when cvxopt is installed); all exact,
        the same skeleton to rounding (:mod:`.solve`, docs/skeletonize.md).
    """

    min_neighbors: int = 8
    max_neighbors: int = 30
    neighbor_fraction: float = 0.012
    contraction_weight: float | None = None
    attraction_weight: float = 1.0
    contraction_scale: float = 3.0
    contraction_weight_max: float = 2048.0
    attraction_weight_max: float = 10000.0
    weight_row_cap: float = 10000.0
    max_iterations: int = 20
    termination_ratio: float = 0.01
    bbox_growth_limit: float = 1.2
    sample_radius_factor: float = 0.02
    fan_start: str = "auto"
    qhull_fan_max_points: int = 25000
    linear_solver: str = "auto"

    def fan_start_for(self, n_points: int) -> str:
        """The fan start used for a cloud of ``n_points`` ("auto" resolved)."""
        if self.fan_start != "auto":
            return self.fan_start
        return "qhull" if n_points <= int(self.qhull_fan_max_points) else "axis"

    def __post_init__(self) -> None:
        def bad(name: str, why: str) -> None:
            raise ValueError(f"skeletonize parameter {name}={getattr(self, name)!r}: {why}")

        if self.linear_solver not in ("auto", "cholmod", "superlu"):
            bad("linear_solver", "must be auto, cholmod or superlu")
        if self.fan_start not in ("auto", "qhull", "axis"):
            bad("fan_start", "must be auto, qhull or axis")
        if int(self.qhull_fan_max_points) < 0:
            bad("qhull_fan_max_points", "must be >= 0")
        for name in ("attraction_weight", "contraction_weight_max", "attraction_weight_max", "weight_row_cap",
                     "termination_ratio", "sample_radius_factor", "neighbor_fraction"):
            if not float(getattr(self, name)) > 0:
                bad(name, "must be > 0")
        if self.contraction_weight is not None and not float(self.contraction_weight) > 0:
            bad("contraction_weight", "must be > 0 or None")
        if not float(self.contraction_scale) >= 1.0:
            bad("contraction_scale", "must be >= 1")
        if not float(self.bbox_growth_limit) > 1.0:
            bad("bbox_growth_limit", "must be > 1")
        if int(self.min_neighbors) < 3 or int(self.max_neighbors) < int(self.min_neighbors):
            bad("min_neighbors", "must be >= 3 and <= max_neighbors")
        if int(self.max_iterations) < 1:
            bad("max_iterations", "must be >= 1")



@dataclass(frozen=True)
class SkeletonizeParams(_Replaceable):
    """Constants of the skeletonizer; defaults follow Cao et al.'s toolbox (``GS.m``) where it has one.

    Attributes
    ----------
    laplacian_neighbors : candidate neighbours per point for robust_laplacian's local Delaunay
        one-rings (its default, 30).
    mollify_factor : robust_laplacian's intrinsic mollification (its default, 1e-5).
    contraction_weight : initial contraction weight W_L; None = sqrt(N / reference_points) /
        (5 x mean one-ring edge length) in normalized units: the toolbox's
        ``compute_init_laplacian_constraint_weight`` made density independent (the cotangent
        Laplacian scales with the area per point).
    reference_points : cloud size at which the default W_L and its cap equal the toolbox's (4096,
        the paper's clouds).
    contraction_scale : W_L is multiplied by this each iteration (s_L = 3, toolbox; the paper says 2).
    contraction_weight_max : cap on W_L (2048, from Au et al.'s implementation), scaled by
        sqrt(N / reference_points) like the start.
    attraction_weight : initial attraction weight W_H (1).
    attraction_weight_max : cap on W_H (10000).
    max_iterations : contraction iterations at most (20, toolbox).
    termination_ratio : stop when the mean one-ring size ratio (current / original) decreased by less
        than this in the last iteration (0.01, toolbox's ``CONTRACT_TERMINATION_CONDITION``) ...
    started_ratio : ... and that ratio is already below this (0.9): unlike the toolbox, a first
        iteration that hardly moved anything does not end the contraction.
    bbox_growth_limit : an iteration whose result's bounding box (0.1%-99.9% quantiles) grows on any axis by more than
        (factor - 1) x the original's longest side is rejected and contraction stops (1.2; the
        toolbox compares each axis with itself, which stops flat shapes early).
    sample_radius_factor : ball radius of the farthest-point sampling = factor x bounding-box diagonal
        of the normalized cloud (0.02, as the paper's demo).
    connect_neighbors : original-cloud kNN neighbours whose ball labels connect two samples; None =
        the one-ring neighbours of the Laplacian (Cao's "inherited" connectivity).
    short_cycle_factor : after triangles are gone, cycles shorter (total edge length) than this x the
        sample radius are collapsed, shortest edge first: two strands of samples along a tube that
        did not contract to a line, or quads left in a flat cap. A real hole (torus: ~80 radii) is longer.
        0 keeps every cycle.
    shortcut_ratio : before collapsing, an edge is dropped when another path joins its ends at most
        this x its length (a shortcut along a line of samples, e.g. the long side of a triangle
        with an angle above ~100 degrees); 1 = Cao's plain collapse.
    prune_branch_factor : leaf branches shorter than this x the sample radius that hang off a
        junction are removed (end-cap spurs); 0 keeps them.
    prune_thickness_factor : ... as are leaf branches shorter than this x the shape's thickness at
        their junction (mean distance of the junction's original points to it): a flat end cap
        contracts to a cross as wide as the tube; 0 turns this off.
    min_sample_points : a sample ball holding fewer contracted points than this is dropped with its
        points when it is isolated or a leaf on an edge longer than two radii (stray points thrown
        out of the shape would add long spokes to the curve).
    linear_solver : the contraction's solve: "cholmod" (CHOLMOD from cvxopt), "superlu" (SciPy's
        ``spsolve``) or "auto" (cholmod when cvxopt is installed); the same skeleton to rounding.
    """

    laplacian_neighbors: int = 30
    mollify_factor: float = 1e-5
    contraction_weight: float | None = None
    contraction_scale: float = 3.0
    contraction_weight_max: float = 2048.0
    reference_points: int = 4096
    attraction_weight: float = 1.0
    attraction_weight_max: float = 10000.0
    max_iterations: int = 20
    termination_ratio: float = 0.01
    started_ratio: float = 0.9
    bbox_growth_limit: float = 1.2
    sample_radius_factor: float = 0.02
    connect_neighbors: int | None = None
    short_cycle_factor: float = 20.0
    shortcut_ratio: float = 1.3
    prune_branch_factor: float = 3.0
    prune_thickness_factor: float = 1.0
    min_sample_points: int = 3
    linear_solver: str = "auto"

    def __post_init__(self) -> None:
        def bad(name: str, why: str) -> None:
            raise ValueError(f"skeletonize parameter {name}={getattr(self, name)!r}: {why}")

        if self.linear_solver not in ("auto", "cholmod", "superlu"):
            bad("linear_solver", "must be auto, cholmod or superlu")

        for name in ("mollify_factor", "contraction_weight_max", "attraction_weight",
                     "attraction_weight_max", "termination_ratio", "sample_radius_factor"):
            if not float(getattr(self, name)) > 0:
                bad(name, "must be > 0")
        if self.contraction_weight is not None and not float(self.contraction_weight) > 0:
            bad("contraction_weight", "must be > 0 or None")
        if not 0.0 < float(self.started_ratio) <= 1.0:
            bad("started_ratio", "must be in (0, 1]")
        if int(self.reference_points) < 1:
            bad("reference_points", "must be >= 1")
        if not float(self.contraction_scale) >= 1.0:
            bad("contraction_scale", "must be >= 1")
        if not float(self.bbox_growth_limit) > 1.0:
            bad("bbox_growth_limit", "must be > 1")
        if int(self.laplacian_neighbors) < 3:
            bad("laplacian_neighbors", "must be >= 3")
        if int(self.max_iterations) < 1:
            bad("max_iterations", "must be >= 1")
        if self.connect_neighbors is not None and int(self.connect_neighbors) < 2:
            bad("connect_neighbors", "must be >= 2 or None")
        if not float(self.shortcut_ratio) >= 1.0:
            bad("shortcut_ratio", "must be >= 1")
        if float(self.prune_thickness_factor) < 0:
            bad("prune_thickness_factor", "must be >= 0")
        if float(self.prune_branch_factor) < 0:
            bad("prune_branch_factor", "must be >= 0")
        if int(self.min_sample_points) < 1:
            bad("min_sample_points", "must be >= 1")
        if float(self.short_cycle_factor) < 0:
            bad("short_cycle_factor", "must be >= 0")



@dataclass(frozen=True)
class AxisParams:
    """Constants of the axis curve (:mod:`.local_axis`) and of the default pipeline's choice (:mod:`.default`).

    ``neighbors`` k of the centroids (16); ``iterations`` of the moves (12); ``linearity`` above which
    the move along the main axis is removed ((l1 - l2) / l1 of the neighbourhood's covariance, 0.5);
    ``sample_spacings`` the sampling ball's radius in spacings (3); ``connect_neighbors`` the nearest
    cloud neighbours whose samples are joined (8); ``thin_ratio``: the default pipeline takes the axis
    curve instead of cao's when cao's sampling ball (``CaoParams.sample_radius_factor`` x the bounding
    box's diagonal) exceeds this many local thicknesses (4; calibrated on the generated suites, where it
    stays below 1: docs/skeletonize.md "Thin parts") and the thickness is at least ``thin_min_spacings``
    spacings (1.5: a surface scan's points hardly move, a tube's move by its radius). ``curve``: "rings"
    (:mod:`.axis_rings`: bands of ``ring_width`` spacings of geodesic distance on the moved points' kNN
    graph of ``ring_neighbors``, each band's parts joined over ``ring_connect`` neighbours, degree-2
    vertices within ``simplify_spacings`` of their neighbours' segment, at most ``simplify_longest``
    long, dropped; a band part's vertex is its points' centroid weighted by their depth, the distance
    to the nearest cloud point, to ``ring_depth_power``: 2, chosen on two neurons, docs/skeletonize.md
    "Thin parts"; 0 the plain centroid) or "balls" (the ball samples above)."""

    neighbors: int = 16
    iterations: int = 12
    linearity: float = 0.5
    sample_spacings: float = 3.0
    connect_neighbors: int = 8
    thin_ratio: float = 4.0
    thin_min_spacings: float = 1.5
    curve: str = "rings"
    ring_neighbors: int = 16
    ring_width: float = 1.0
    ring_connect: int = 48
    simplify_spacings: float = 0.25
    simplify_longest: float = 4.0
    ring_depth_power: float = 2.0



@dataclass
class SkeletonizeInfo:
    """What happened: iterations run, the one-ring size ratio after each, why it stopped, timings,
    the method and (cao) its initial contraction weight W_L and where its closed one-rings started."""

    iterations: int
    ring_ratios: list[float]
    stop_reason: str
    sample_radius: float
    n_samples: int
    timings: dict[str, float]
    method: str = "skelscope"
    initial_weight: float | None = None
    fan_start: str | None = None


# ---------------------------------------------------------------------------------------------
# progress plumbing


class Reporter:
    """Maps stage fractions onto one overall fraction and raises ``Cancelled`` when asked to."""

    _SPAN = {"laplacian": (0.0, 0.1), "contraction": (0.1, 0.85), "curve": (0.85, 1.0)}

    def __init__(self, progress: Progress | None, cancel: Callable[[], bool] | None) -> None:
        self.progress = progress
        self.cancel = cancel
        self._last = -1.0

    def __call__(self, stage: str, fraction: float) -> None:
        if self.cancel is not None and self.cancel():
            raise Cancelled(f"cancelled during skeletonization ({stage})")
        if self.progress is not None:
            lo, hi = self._SPAN[stage]
            overall = lo + (hi - lo) * min(max(fraction, 0.0), 1.0)
            if overall - self._last >= 0.005 or overall >= 1.0:
                self._last = overall
                self.progress(overall, stage)


# ---------------------------------------------------------------------------------------------
# one-rings and the Laplacian


def method_params(method: str | None, values: dict | None = None) -> "tuple[str, CaoParams | SkeletonizeParams]":
    """The built-in method's name and its parameters from plain values (manifests, the study, the
    CLI): ``"cao"`` (the default) takes :class:`CaoParams`, ``"skelscope"`` :class:`SkeletonizeParams`.
    Unknown methods or fields raise ``ValueError``."""
    name = "cao" if method is None else str(method)
    if name not in ("cao", "skelscope"):
        raise ValueError(f"unknown skeletonize method {name!r}: use cao or skelscope")
    cls = CaoParams if name == "cao" else SkeletonizeParams
    return name, cls().replace(**(values or {}))
