"""Trust checks: conditions under which the paper's scores say nothing (issue 8; docs/metrics.md
"Warnings"). Each is a :class:`TrustWarning` with a stable ``code``:

- ``frame``: the skeleton lies mostly outside the cloud's bounding box, or its extent is more than
  ``frame_extent_ratio`` times larger (or, while outside, smaller) than the cloud's: other units;
  or, inside but mostly unbounded, some mapping (scale, offset) found from its bounding box makes it
  bounded and complete (voxel coordinates of a grid laid over the cloud: kimimaro, scikit-image).
- ``collapse``: the skeleton spans under ``collapse_extent`` of the cloud's extent (d_B and
  centeredness reward a skeleton shrunk to a point).
- ``trivial_smoothness``: no degree-2 vertex, so the curve's smoothness is 1 by definition.
- ``no_correspondence``: topology and skeletal centeredness could not be computed.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize
from scipy.spatial import cKDTree

from .diagnostics.warning import TrustWarning
from .geometry import bounding_box
from .params import Params

__all__ = ["TrustWarning", "FrameFit", "fit_frame", "frame_warnings", "frame_fit_warning", "bbox_transform",
           "smoothness_warning", "no_correspondence_warning"]

_FRAME_HINT = "map it with --skeleton-scale S --skeleton-offset X Y Z"
# the frame fit: skeleton points for its objective and completeness, cloud points, boundedness runs at most
FIT_POINTS = 2000
FIT_CLOUD = 16384
FIT_TRIES = 4


def _diag(points: np.ndarray) -> float:
    if not len(points):
        return 0.0
    lo, hi = bounding_box(points)
    return float(np.linalg.norm(hi - lo))


def frame_warnings(cloud: np.ndarray, skeleton: np.ndarray, what: str, params: Params = Params()) -> list[TrustWarning]:
    """``frame`` / ``collapse`` for one skeleton's points (both arrays in the user's units)."""
    lo, hi = bounding_box(cloud)
    d_cloud = float(np.linalg.norm(hi - lo))  # = _diag(cloud)
    margin = 0.1 * d_cloud
    inside = np.all((skeleton >= lo - margin) & (skeleton <= hi + margin), axis=1)
    frac_inside = float(inside.mean())
    d_skel = _diag(skeleton)
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
        out.append(TrustWarning("frame", f"the {what} seems to be in another frame: {'; '.join(why)}; "
                                         + _hint(cloud, skeleton)))
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


def _hint(cloud: np.ndarray, skeleton: np.ndarray) -> str:
    t = bbox_transform(cloud, skeleton)
    if t is None:
        return _FRAME_HINT
    s, off = t
    return (f"{_FRAME_HINT} (bounding boxes match with --skeleton-scale {s:.6g} "
            f"--skeleton-offset {off[0]:.6g} {off[1]:.6g} {off[2]:.6g})")


@dataclass(frozen=True)
class FrameFit:
    """A mapping x -> ``scale`` x + ``offset`` under which the skeleton is bounded (share ``bounded`` of
    its points) and complete (``completeness``, no missing part: docs/diagnostics.md "Frame")."""

    scale: float
    offset: np.ndarray
    bounded: float
    completeness: float


def fit_frame(
    cloud: np.ndarray, skeleton: np.ndarray, bounded_now: float, bounded_fraction, params: Params = Params()
) -> FrameFit | None:
    """The mapping of a skeleton in another frame onto the cloud (both arrays in the user's units), or None.

    Only tried when the skeleton is under half bounded (``bounded_now`` < 0.5). Starts: its bounding
    box centred on the cloud's and scaled to its diagonal (x 1, 0.85, 0.7: a skeleton's box is smaller
    by the shape's thickness); each is refined by maximizing the skeleton points' mean distance to the
    cloud (a medial curve is as far from the surface as it can be; points leaving the cloud's box
    count negative), Nelder-Mead on log scale and offset. Candidates are tried best first (at most
    ``FIT_TRIES`` boundedness runs on <= 200 points): the first with ``bounded_fraction(points)`` >=
    beta* and 0.25 above ``bounded_now`` AND no missing part (``incomplete``; a shrunk mapping is
    bounded but leaves the shape's ends unexplained) is returned."""
    # the diagnostics import this module (TrustWarning); imported here, when a fit is tried, no cycle at import
    from .diagnostics.missing_parts import missing_parts

    d_cloud, d_skel = _diag(cloud), _diag(skeleton)
    if not (d_cloud > 0 and d_skel > 0) or bounded_now >= 0.5:
        return None
    s0, _ = bbox_transform(cloud, skeleton)  # type: ignore[misc]
    rows = np.linspace(0, len(skeleton) - 1, min(len(skeleton), FIT_POINTS)).astype(int)
    pts = np.asarray(skeleton, dtype=float)[rows]
    pick = pts[np.linspace(0, len(pts) - 1, min(len(pts), 200)).astype(int)]
    sub = cloud if len(cloud) <= FIT_CLOUD else cloud[np.random.default_rng(0).choice(len(cloud), FIT_CLOUD, replace=False)]
    tree = cKDTree(sub)
    lo, hi = bounding_box(cloud)
    centre_c = (lo + hi) / 2
    centre_s = (skeleton.min(axis=0) + skeleton.max(axis=0)) / 2
    step = 0.01 * d_cloud

    def fit_value(x: np.ndarray) -> float:
        s, off = np.exp(x[0]), x[1:] * step
        q = pts * s + off
        d = tree.query(q)[0]
        out = np.linalg.norm(np.maximum(lo - q, 0) + np.maximum(q - hi, 0), axis=1)
        return float(np.mean(np.where(out > 0, -out, d)))

    cands = []
    for f in (1.0, 0.85, 0.7):
        sc = s0 * f
        x0 = np.concatenate([[np.log(sc)], (centre_c - sc * centre_s) / step])
        simplex = np.vstack([x0] + [x0 + np.eye(4)[k] * (0.05 if k == 0 else 1.0) for k in range(4)])
        res = minimize(lambda x: -fit_value(x), x0, method="Nelder-Mead",
                       options={"initial_simplex": simplex, "xatol": 1e-3, "fatol": 1e-9 * d_cloud, "maxfev": 600})
        cands += [(fit_value(res.x), res.x), (fit_value(x0), x0)]
    cands.sort(key=lambda c: -c[0])
    tried: list[np.ndarray] = []
    for _, x in cands:
        if len(tried) >= FIT_TRIES:
            break
        if any(np.allclose(x, t, atol=1e-3) for t in tried):
            continue
        tried.append(x)
        s, off = float(np.exp(x[0])), x[1:] * step
        after = float(bounded_fraction(pick * s + off))
        if not (after >= params.beta_star and after >= bounded_now + 0.25):
            continue
        mp = missing_parts(sub, pts * s + off, params)
        if mp.counted:
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
