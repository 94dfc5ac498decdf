"""Trust checks: conditions under which the paper's scores say nothing (issue 8; docs/metrics.md
"Warnings"). Each is a :class:`TrustWarning` with a stable ``code``:

- ``frame``: the skeleton lies mostly outside the cloud's bounding box, or its extent is more than
  ``frame_extent_ratio`` times larger (or, while outside, smaller) than the cloud's: other units;
  or, inside but mostly unbounded, it becomes bounded once its bounding box is mapped onto the
  cloud's (voxel coordinates of a grid laid over the cloud: kimimaro, scikit-image).
- ``collapse``: the skeleton spans under ``collapse_extent`` of the cloud's extent (d_B and
  centeredness reward a skeleton shrunk to a point).
- ``trivial_smoothness``: no degree-2 vertex, so the curve's smoothness is 1 by definition.
- ``no_correspondence``: topology and skeletal centeredness could not be computed.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from .geometry import bounding_box
from .params import Params

__all__ = ["TrustWarning", "frame_warnings", "frame_fit_warning", "bbox_transform", "smoothness_warning",
           "no_correspondence_warning"]

_FRAME_HINT = "map it with --skeleton-scale S --skeleton-offset X Y Z"


_NUMBER = r"([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)"
_MAPPING = re.compile(rf"--skeleton-scale {_NUMBER} --skeleton-offset {_NUMBER} {_NUMBER} {_NUMBER}")
#: where a message's command-line remedy starts (what precedes it is the finding)
_REMEDIES = ("; give --skeletal-index", "; " + "map it with --skeleton-scale", " (or, if it is in other units, ")


@dataclass(frozen=True)
class TrustWarning:
    """``message`` is the text the CLI prints and the JSON stores, with the command line's remedy.
    ``finding`` (what was found) and ``mapping`` (the suggested ``(scale, offset)`` into the cloud's
    frame, or None) are read from it, for a front end that words its own remedy (the viewer names its
    menus and settings, issue 25); a warning read back from a file gives the same."""

    code: str
    message: str

    def to_dict(self) -> dict[str, str]:
        return {"code": self.code, "message": self.message}

    @property
    def finding(self) -> str:
        cut = [i for i in (self.message.find(r) for r in _REMEDIES) if i >= 0]
        return self.message[: min(cut)] if cut else self.message

    @property
    def mapping(self) -> tuple[float, tuple[float, float, float]] | None:
        m = _MAPPING.search(self.message)
        if m is None:
            return None
        s, x, y, z = (float(v) for v in m.groups())
        return s, (x, y, z)


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


def frame_fit_warning(
    cloud: np.ndarray, skeleton: np.ndarray, bounded_now: float, bounded_fraction, what: str, params: Params = Params()
) -> list[TrustWarning]:
    """``frame`` for a skeleton inside the cloud's box but mostly unbounded (fraction ``bounded_now``
    of its elements < 0.5) when centring its bounding box on the cloud's and scaling it to the
    cloud's diagonal (x 1, 0.85, 0.7) makes it bounded: ``bounded_fraction(points)`` (user units)
    >= beta* and 0.25 higher. Only tried in that suspicious case (<= 3 runs on <= 200 points)."""
    d_cloud, d_skel = _diag(cloud), _diag(skeleton)
    if not (d_cloud > 0 and d_skel > 0) or bounded_now >= 0.5:
        return []
    ratio = d_skel / d_cloud
    s0, _ = bbox_transform(cloud, skeleton)  # type: ignore[misc]
    pick = skeleton if len(skeleton) <= 200 else skeleton[np.linspace(0, len(skeleton) - 1, 200).astype(int)]
    centre_c = (cloud.min(axis=0) + cloud.max(axis=0)) / 2
    centre_s = (skeleton.min(axis=0) + skeleton.max(axis=0)) / 2
    # a skeleton's box is smaller than its cloud's by the shape's thickness: try a few shrinks
    best, best_s = -1.0, s0
    for f in (1.0, 0.85, 0.7):
        sc = s0 * f
        after = float(bounded_fraction((pick - centre_s) * sc + centre_c))
        if after > best:
            best, best_s = after, sc
    if best >= params.beta_star and best >= bounded_now + 0.25:
        off = centre_c - best_s * centre_s
        return [TrustWarning(
            "frame",
            f"the {what} seems to be in another frame: {bounded_now:.0%} of it is bounded, {best:.0%} once "
            f"its bounding box (extent {ratio:.3g} x the cloud's) is centred on the cloud's and scaled by "
            f"{best_s:.6g}; {_FRAME_HINT} (e.g. --skeleton-scale {best_s:.6g} --skeleton-offset "
            f"{off[0]:.6g} {off[1]:.6g} {off[2]:.6g})",
        )]  # fmt: skip
    return []


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
