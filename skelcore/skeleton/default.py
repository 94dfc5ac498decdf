"""The curve ``skelcore skeletonize`` starts from by default (before its repair; docs/skeletonize.md
"Thin parts"): cao's, unless the cloud's parts are too thin for cao's sampling ball. The cloud is
first moved onto its local axes (:func:`.local_axis.axis_contract`, a few seconds at 100k points);
the median move is the local thickness. When cao's ball (``sample_radius_factor`` x the bounding
box's diagonal) exceeds ``AxisParams.thin_ratio`` thicknesses, one ball would swallow whole branches
(a neuron: a ball of 730 units over dendrites of radius 20), so the axis curve of those moved points
is taken and cao is not run, provided the thickness is ``thin_min_spacings`` spacings or more (on a
surface scan the points hardly move); otherwise cao runs unchanged (``--raw`` is always cao's curve).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..curve import CurveSkeleton
from ..errors import Cancelled
from ..geometry import as_points
from .local_axis import axis_contract, axis_curve, local_thickness
from .pipeline import skeletonize
from .skeleton_params import AxisParams, CaoParams, Progress, SkeletonizeInfo

__all__ = ["DefaultChoice", "default_skeleton"]


@dataclass
class DefaultChoice:
    """Which curve was taken ("cao" or "axis"), the ratio of cao's ball to the local thickness that
    decided it, the thickness and the spacing (cloud units)."""

    method: str
    ratio: float
    thickness: float
    spacing: float


def default_skeleton(cloud: np.ndarray, progress: Progress | None = None, cancel: Callable[[], bool] | None = None,
                     *, cao: CaoParams | None = None, axis: AxisParams | None = None
                     ) -> tuple[np.ndarray, CurveSkeleton, SkeletonizeInfo, DefaultChoice]:
    """(skeletal, curve, info, choice) of the default pipeline's skeletonization (module docstring)."""
    t0 = time.perf_counter()
    pts = as_points("cloud", cloud)
    cao, axis = cao or CaoParams(), axis or AxisParams()

    def check(fraction: float) -> None:
        if cancel is not None and cancel():
            raise Cancelled("cancelled during skeletonization (axes)")
        if progress is not None:
            progress(0.5 * fraction, "axes")

    moved = axis_contract(pts, axis, check)
    thickness = local_thickness(pts, moved)
    ball = float(cao.sample_radius_factor) * float(np.linalg.norm(np.ptp(pts, axis=0)))
    ratio = ball / max(thickness, 1e-12 * max(ball, 1e-300))
    if ratio <= float(axis.thin_ratio) or thickness < float(axis.thin_min_spacings) * moved.spacing:
        skeletal, curve, info = skeletonize(pts, cao, progress, cancel, method="cao", return_info=True)
        return skeletal, curve, info, DefaultChoice("cao", ratio, thickness, moved.spacing)
    t1 = time.perf_counter()
    curve = axis_curve(moved, axis, pts)
    band = float(axis.ring_width if axis.curve == "rings" else axis.sample_spacings)
    info = SkeletonizeInfo(iterations=int(axis.iterations), ring_ratios=[], stop_reason="axis curve (thin parts)",
                           sample_radius=band * moved.spacing, n_samples=int(curve.n_vertices),
                           timings={"contraction": t1 - t0, "curve": time.perf_counter() - t1,
                                    "total": time.perf_counter() - t0}, method="axis")
    if progress is not None:
        progress(1.0, "curve")
    return moved.points, curve, info, DefaultChoice("axis", ratio, thickness, moved.spacing)
