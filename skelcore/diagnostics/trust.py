"""Trust checks: conditions under which the paper's scores say nothing (docs/metrics.md
"Warnings"). Each is a :class:`TrustWarning` with a stable ``code``:

- ``frame``: the skeleton lies mostly outside the cloud's bounding box, or its extent is more than
  ``frame_extent_ratio`` times larger (or, while outside, smaller) than the cloud's: other units;
  or, inside but mostly unbounded, some mapping (scale, offset) found from its bounding box makes it
  bounded and complete (voxel coordinates of a grid laid over the cloud: kimimaro, scikit-image).
- ``collapse``: the skeleton spans under ``collapse_extent`` of the cloud's extent (d_B and
  centeredness reward a skeleton shrunk to a point).
- ``trivial_smoothness``: no degree-2 vertex, so the curve's smoothness is 1 by definition.
- ``no_correspondence``: topology and skeletal centeredness could not be computed.

And which warning codes are a skeleton's defects (:data:`DEFECT_CODES`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..geometry import bounding_box
from ..params import Params
from .trust_warning import TrustWarning

__all__ = ["TrustWarning", "DEFECT_CODES", "defect_codes", "robust_box", "FrameFit", "fit_frame", "frame_warnings", "frame_fit_warning", "bbox_transform",
           "smoothness_warning", "no_correspondence_warning"]

_FRAME_HINT = "map it with --skeleton-scale S --skeleton-offset X Y Z"
# the frame fit: skeleton points it maps, cloud points (completeness), cloud points probing the gap,
# objective evaluations per start (about 2 s in all on a loaded 2-core machine; docs/diagnostics.md "Frame")
FIT_POINTS = 300
FIT_CLOUD = 16384
FIT_PROBES = 1024
FIT_EVALUATIONS = 250
# the leaf size of the cloud's KD-tree, which the objective asks for each mapped point's nearest cloud point:
# points on or near a medial axis are nearly equidistant from many leaves, and 64 points a leaf visits fewer
# of them than scipy's 16 (the same distances; docs/performance.md 6.14)
FIT_TREE_LEAF = 64


def robust_box(points: np.ndarray, quantile: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) corners of the box from the ``quantile`` to the 1 - ``quantile`` quantile of each
    coordinate (0: the bounding box): a few stray points do not stretch it (docs/metrics.md 6)."""
    points = np.asarray(points, dtype=float)
    if quantile <= 0 or len(points) < 2:
        return bounding_box(points)
    lo, hi = np.quantile(points, [quantile, 1.0 - quantile], axis=0)
    return lo, hi


def _diag(points: np.ndarray, quantile: float = 0.0) -> float:
    if not len(points):
        return 0.0
    lo, hi = robust_box(points, quantile)
    return float(np.linalg.norm(hi - lo))


def frame_warnings(cloud: np.ndarray, skeleton: np.ndarray, what: str, params: Params = Params(),
                   bounded_fraction: Callable[[np.ndarray], float] | None = None,
                   cloud_box: tuple[np.ndarray, np.ndarray] | None = None) -> list[TrustWarning]:
    """``frame`` / ``collapse`` for one skeleton's points (both arrays in the user's units). A ``frame``
    message proposes a scale and offset only when :func:`fit_frame` finds one under which the skeleton
    is bounded and complete (``bounded_fraction(points)``: the share of points bounded, by default
    the rays boundedness against this cloud). ``cloud_box``: the cloud's ``robust_box`` at the params'
    quantile when already known (an edit's update keeps it)."""
    q = float(params.trust_extent_quantile)  # stray points stretch neither box (docs/metrics.md 6)
    lo, hi = robust_box(cloud, q) if cloud_box is None else cloud_box
    d_cloud = float(np.linalg.norm(hi - lo))  # = _diag(cloud, q)
    margin = 0.1 * d_cloud
    inside = np.all((skeleton >= lo - margin) & (skeleton <= hi + margin), axis=1)
    frac_inside = float(inside.mean())
    d_skel = _diag(skeleton, q)
    ratio = d_skel / d_cloud if d_cloud > 0 else np.inf
    out: list[TrustWarning] = []
    outside = frac_inside < params.frame_inside_fraction
    big = ratio > params.frame_extent_ratio
    small = ratio < 1.0 / params.frame_extent_ratio
    if outside or big:
        why = []
        if outside:
            why.append(f"only {frac_inside:.0%} of its points lie inside the cloud's bounding box")
        if big or small:
            why.append(f"its extent is {ratio:.3g} x the cloud's")
        bf = bounded_fraction or _bounded_fraction(cloud, params)
        out.append(TrustWarning("frame", f"the {what} seems to be in another frame: {'; '.join(why)}; "
                                         + _hint(fit_frame(cloud, skeleton, 0.0, bf, params))))
    elif ratio < params.collapse_extent:
        out.append(TrustWarning(
            "collapse",
            f"the {what} spans {ratio:.3g} of the cloud's extent (bounding-box diagonals): a collapsed "
            "skeleton scores well on topology, boundedness and centeredness; see the coverage row"
            + (f" (or, if it is in other units, {_FRAME_HINT})" if small else ""),
        ))  # fmt: skip
    return out


def bbox_transform(cloud: np.ndarray, skeleton: np.ndarray) -> tuple[float, np.ndarray] | None:
    """(scale, offset) mapping the skeleton's bounding box (diagonal and centre) onto the cloud's."""
    d_skel = _diag(skeleton)
    if not d_skel > 0:
        return None
    s = _diag(cloud) / d_skel
    off = (cloud.min(axis=0) + cloud.max(axis=0)) / 2 - s * (skeleton.min(axis=0) + skeleton.max(axis=0)) / 2
    return s, off


def _hint(fit: "FrameFit | None") -> str:
    if fit is None:
        return f"{_FRAME_HINT} (no scale and offset found under which it is bounded and complete)"
    off = fit.offset
    return (f"{_FRAME_HINT} (bounded {fit.bounded:.0%}, completeness {fit.completeness:.2f} with "
            f"--skeleton-scale {fit.scale:.6g} --skeleton-offset {off[0]:.6g} {off[1]:.6g} {off[2]:.6g})")


def _bounded_fraction(cloud: np.ndarray, params: Params) -> Callable[[np.ndarray], float]:
    """The share of points (user units) bounded in ``cloud`` (docs/metrics.md 2, as the evaluation scores them)."""
    from ..geometry import Normalization
    from ..metrics.boundedness import boundedness

    norm = Normalization.from_cloud(cloud, params.normalize_by, params.normalized_size)
    cloud_n = norm.apply(cloud)
    return lambda points: float(np.mean(boundedness(cloud_n, norm.apply(points), params=params) > params.beta_star))


@dataclass(frozen=True)
class FrameFit:
    """A mapping x -> ``scale`` x + ``offset`` under which the skeleton is bounded (share ``bounded`` of
    its points) and complete (``completeness``, no missing part: docs/diagnostics.md "Frame")."""

    scale: float
    offset: np.ndarray
    bounded: float
    completeness: float


def fit_frame(
    cloud: np.ndarray, skeleton: np.ndarray, bounded_now: float, bounded_fraction: Callable[[np.ndarray], float],
    params: Params = Params(),
) -> FrameFit | None:
    """The mapping of a skeleton in another frame onto the cloud (both arrays in the user's units), or None.

    Only tried when the skeleton is under half bounded (``bounded_now`` < 0.5). Starts: its bounding
    box centred on the cloud's and scaled to its diagonal (x 1, 0.85, 0.7: a skeleton's box is smaller
    by the shape's thickness), best first by the objective; each is refined (Nelder-Mead on log scale
    and offset) to the least mean gap of the cloud to the mapped skeleton's medial balls (the gap of docs/metrics.md 5.2:
    0 for a medial skeleton that reaches every part; moving it off the axis, shrinking or shifting it
    raise it). A refined mapping is proposed only when ``bounded_fraction(points)`` >= beta* and 0.25
    above ``bounded_now`` and the mapped skeleton is complete (no ``incomplete``: a shrunk mapping is
    bounded but leaves the shape's ends unexplained); the next start is refined otherwise."""
    from scipy.optimize import minimize
    from scipy.spatial import cKDTree

    # imported when a fit is tried (it brings the coverage metric; the trust checks' users rarely fit)
    from .missing_parts import missing_parts

    if bounded_now >= 0.5:  # before the cloud's box: every evaluation and update asks (0.7 ms at 100k)
        return None
    d_cloud, d_skel = _diag(cloud), _diag(skeleton)
    if not (d_cloud > 0 and d_skel > 0):
        return None
    s0, _ = bbox_transform(cloud, skeleton)  # type: ignore[misc]
    skeleton = np.asarray(skeleton, dtype=float)
    pts = skeleton[np.linspace(0, len(skeleton) - 1, min(len(skeleton), FIT_POINTS)).astype(int)]
    pick = pts[np.linspace(0, len(pts) - 1, min(len(pts), 200)).astype(int)]
    rng = np.random.default_rng(0)
    sub = cloud if len(cloud) <= FIT_CLOUD else cloud[rng.choice(len(cloud), FIT_CLOUD, replace=False)]
    probe = sub if len(sub) <= FIT_PROBES else sub[rng.choice(len(sub), FIT_PROBES, replace=False)]
    tree = cKDTree(sub, leafsize=FIT_TREE_LEAF)
    lo, hi = bounding_box(cloud)
    centre_c = (lo + hi) / 2
    centre_s = (skeleton.min(axis=0) + skeleton.max(axis=0)) / 2
    step = 0.01 * d_cloud  # offsets in units of 1 % of the cloud's diagonal: the simplex's scales match
    k = min(8, len(pts))

    def mean_gap(x: np.ndarray) -> float:
        q = pts * np.exp(x[0]) + x[1:] * step
        r = tree.query(q)[0]  # each mapped point's inscribed ball
        d, j = cKDTree(q).query(probe, k=k)  # a probe's gap over its k nearest balls (the minimum is near)
        gap = np.min(d.reshape(len(probe), k) - r[j.reshape(len(probe), k)], axis=1)
        out = np.linalg.norm(np.maximum(lo - q, 0) + np.maximum(q - hi, 0), axis=1)  # outside the cloud's box
        return float(np.mean(np.maximum(gap, 0.0)) + np.mean(out))

    starts = [np.concatenate([[np.log(s0 * f)], (centre_c - s0 * f * centre_s) / step]) for f in (1.0, 0.85, 0.7)]
    for x0 in sorted(starts, key=mean_gap):
        simplex = np.vstack([x0] + [x0 + np.eye(4)[i] * (0.05 if i == 0 else 1.0) for i in range(4)])
        x = minimize(mean_gap, x0, method="Nelder-Mead",
                     options={"initial_simplex": simplex, "xatol": 1e-3, "fatol": 1e-9 * d_cloud,
                              "maxfev": FIT_EVALUATIONS}).x
        s, off = float(np.exp(x[0])), x[1:] * step
        after = float(bounded_fraction(pick * s + off))
        if not (after >= params.beta_star and after >= bounded_now + 0.25):
            continue
        mp = missing_parts(sub, pts * s + off, params)
        if mp.incomplete:
            continue
        return FrameFit(s, off, after, mp.completeness)
    return None


def frame_fit_warning(
    cloud: np.ndarray, skeleton: np.ndarray, bounded_now: float, bounded_fraction, what: str, params: Params = Params()
) -> list[TrustWarning]:
    """``frame`` for a skeleton inside the cloud's box but mostly unbounded (fraction ``bounded_now``
    of its elements < 0.5) when :func:`fit_frame` finds a mapping under which it is bounded and
    complete: voxel coordinates of a grid laid over the cloud (kimimaro, scikit-image)."""
    fit = fit_frame(cloud, skeleton, bounded_now, bounded_fraction, params)
    if fit is None:
        return []
    ratio = _diag(skeleton) / _diag(cloud)
    s, off = fit.scale, fit.offset
    return [TrustWarning(
        "frame",
        f"the {what} seems to be in another frame: {bounded_now:.0%} of it is bounded, {fit.bounded:.0%} "
        f"(completeness {fit.completeness:.2f}) once scaled by {s:.6g} and moved (its extent is {ratio:.3g} x "
        f"the cloud's); {_FRAME_HINT} (e.g. --skeleton-scale {s:.6g} --skeleton-offset "
        f"{off[0]:.6g} {off[1]:.6g} {off[2]:.6g})",
    )]  # fmt: skip


#: Warning codes that say the skeleton itself is wrong, as opposed to caveats about what a
#: score can mean (``trivial_smoothness``, ``no_correspondence``) or about the scan: ``--strict``,
#: compare's "sound" column, the profiles' ``fail_on`` and the CLI's defects block read this set.
#: The scan's warnings stay out: ``open_surface``, ``outliers``, ``thin_parts`` (parts sampled too thinly
#: to resolve) and ``sparse_boundedness`` (boundedness falls where the cloud is sparse) are facts about
#: the cloud, true of every skeleton evaluated on it, not faults of the skeleton.
DEFECT_CODES = frozenset({"frame", "collapse", "incomplete", "spurious_branches", "spurious_cycles",
                          "missing_cycles", "outside", "disconnected", "along_surface"})


def defect_codes(warnings: list[dict[str, str]] | list[TrustWarning]) -> list[str]:
    """The defect codes among ``warnings`` (dicts or TrustWarnings), sorted, each once."""
    codes = {w["code"] if isinstance(w, dict) else w.code for w in warnings}
    return sorted(codes & DEFECT_CODES)


def unchecked_defects(not_computed: dict[str, str] | None) -> dict[str, str]:
    """The defect checks that did not run (``Evaluation.not_computed`` entries named by a defect
    code) -> why: a block of defects names them, so that "none found" never hides a check left out
    (docs/diagnostics.md "Checks not run")."""
    return {k: str(v) for k, v in (not_computed or {}).items() if k in DEFECT_CODES}


def smoothness_warning(degrees: np.ndarray) -> list[TrustWarning]:
    """``trivial_smoothness`` when the curve has no degree-2 vertex."""
    if np.count_nonzero(np.asarray(degrees) == 2) == 0:
        return [TrustWarning(
            "trivial_smoothness",
            "the curve skeleton has no degree-2 vertex: its smoothness is 1 by definition and says nothing",
        )]  # fmt: skip
    return []


def no_correspondence_warning(n_skeletal: int, n_cloud: int) -> TrustWarning:
    return TrustWarning(
        "no_correspondence",
        f"the skeletal set has {n_skeletal} points and the cloud {n_cloud}: topology and skeletal "
        "centeredness need a correspondence; give --skeletal-index F or --correspondence reverse",
    )
