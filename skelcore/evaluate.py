"""Orchestration: normalize, run each metric, map progress, honour cancel, time each stage."""

from __future__ import annotations

import time
from typing import Callable

import numpy as np

from .curve import CurveSkeleton
from .curve_sampling import sample_curve
from .errors import Cancelled, SkelInputError
from .geometry import Normalization, as_points
from .metrics.boundedness import boundedness
from .metrics.centeredness import curve_centeredness, skeletal_centeredness
from .metrics.smoothness import curve_smoothness_overall, curve_vertex_smoothness, skeletal_smoothness
from .metrics.topology import topological_similarity
from .params import Params
from .results import CurveLocal, Evaluation, SkeletalLocal

Progress = Callable[[float, str], None]

# Relative cost of each stage, for a progress bar that moves evenly (measured on 4k-point shapes).
_WEIGHTS = {
    "topology": 1.0,
    "skeletal boundedness": 4.0,
    "skeletal centeredness": 0.5,
    "skeletal smoothness": 0.5,
    "curve boundedness": 1.0,
    "curve centeredness": 1.0,
    "curve smoothness": 0.1,
}


class _Stages:
    """Turns per-stage fractions into one overall fraction; checks ``cancel`` at every call."""

    def __init__(self, names: list[str], progress: Progress | None, cancel: Callable[[], bool] | None):
        total = sum(_WEIGHTS[n] for n in names) or 1.0
        self._start: dict[str, float] = {}
        acc = 0.0
        for n in names:
            self._start[n] = acc / total
            acc += _WEIGHTS[n]
        self._size = {n: _WEIGHTS[n] / total for n in names}
        self._progress = progress
        self._cancel = cancel
        self._last = -1.0
        self._last_stage = ""
        self.timings: dict[str, float] = {}

    def checkpoint(self, stage: str) -> Callable[[float], None]:
        def check(fraction: float) -> None:
            if self._cancel is not None and self._cancel():
                raise Cancelled(f"cancelled during {stage}")
            if self._progress is not None:
                overall = self._start[stage] + self._size[stage] * min(max(fraction, 0.0), 1.0)
                # throttled (Orange3's habit), but a new stage is shown at once: the label names
                # the stage that runs
                if stage != self._last_stage or overall - self._last >= 0.005 or fraction >= 1.0:
                    overall = max(overall, self._last)  # never back by a rounding error
                    self._last = overall
                    self._last_stage = stage
                    self._progress(overall, stage)

        return check

    def run(self, stage: str, fn, *args, **kwargs):
        check = self.checkpoint(stage)
        check(0.0)
        t0 = time.perf_counter()
        out = fn(*args, checkpoint=check, **kwargs)
        self.timings[stage] = time.perf_counter() - t0
        check(1.0)
        return out


def evaluate(
    cloud: np.ndarray,
    skeletal: np.ndarray | None = None,
    curve: CurveSkeleton | tuple | None = None,
    params: Params = Params(),
    progress: Progress | None = None,
    cancel: Callable[[], bool] | None = None,
    *,
    skeletal_index: np.ndarray | None = None,
    inputs: dict | None = None,
) -> Evaluation:
    """Score a skeleton against its point cloud with the paper's four metrics (SPEC.md).

    Parameters
    ----------
    cloud : (N_o, 3) original cloud, user units.
    skeletal : (N_s, 3) skeletal point set with pointwise correspondence (row i of the skeletal set
        is where cloud row i went); N_s must equal N_o unless ``skeletal_index`` maps skeletal rows
        to cloud rows.
    curve : a :class:`CurveSkeleton` or a ``(vertices, edges)`` pair.
    progress : ``progress(fraction, stage)``, called at checkpoints (throttled).
    cancel : returning True makes the next checkpoint raise :class:`Cancelled`.

    Examples
    --------
    >>> ev = evaluate(cloud, skeletal=contracted)          # doctest: +SKIP
    >>> ev.summary()["boundedness"]["skeletal"]            # doctest: +SKIP
    """
    t_start = time.perf_counter()
    cloud = as_points("cloud", cloud)
    if len(cloud) < 2:
        raise SkelInputError("cloud: at least 2 points are needed")
    try:
        norm = Normalization.from_cloud(cloud, params.normalize_by, params.normalized_size)
    except ValueError:
        raise SkelInputError("cloud: all points coincide") from None
    cloud_n = norm.apply(cloud)

    skel = skel_n = None
    correspondence = None
    if skeletal is not None:
        skel = as_points("skeletal point set", skeletal)
        if skeletal_index is not None:
            correspondence = np.asarray(skeletal_index, dtype=np.int64).ravel()
            if correspondence.shape != (len(skel),):
                raise SkelInputError("skeletal index: needs one cloud row per skeletal point")
            if correspondence.min() < 0 or correspondence.max() >= len(cloud):
                raise SkelInputError("skeletal index: cloud row out of range")
        elif len(skel) != len(cloud):
            raise SkelInputError(
                f"skeletal point set has {len(skel)} points but the cloud has {len(cloud)}: "
                "pointwise correspondence needs equal counts"
            )
        skel_n = norm.apply(skel)

    curve_obj: CurveSkeleton | None = None
    if curve is not None:
        curve_obj = curve if isinstance(curve, CurveSkeleton) else CurveSkeleton.from_raw(*curve)

    names: list[str] = []
    if skel is not None:
        names += ["topology", "skeletal boundedness", "skeletal centeredness", "skeletal smoothness"]
    if curve_obj is not None:
        names += ["curve boundedness", "curve centeredness", "curve smoothness"]
    stages = _Stages(names, progress, cancel)
    p = params

    ev = Evaluation(params=p, normalization=norm, cloud=cloud, inputs=dict(inputs or {}))
    if skel is not None:
        ev.topology = stages.run("topology", topological_similarity, cloud_n, skel_n, params=p)
        beta = stages.run("skeletal boundedness", boundedness, cloud_n, skel_n, params=p)
        corr_cloud = cloud_n if correspondence is None else cloud_n[correspondence]
        c_raw = stages.run("skeletal centeredness", skeletal_centeredness, corr_cloud, skel_n, params=p)
        smooth = stages.run("skeletal smoothness", skeletal_smoothness, skel_n, params=p)
        ev.skeletal = SkeletalLocal(points=skel, boundedness=beta, centeredness_raw=c_raw, smoothness=smooth)

    if curve_obj is not None:
        curve_n = curve_obj.transformed(norm.apply)
        samples = sample_curve(curve_n, p.curve_samples, collinear_cos=p.collinear_cos)
        beta_c = stages.run("curve boundedness", boundedness, cloud_n, samples.points, params=p)
        c_raw_c = stages.run(
            "curve centeredness", curve_centeredness, cloud_n, samples.points, samples.directions, params=p
        )

        def _smooth(curve_n: CurveSkeleton, checkpoint) -> tuple:
            s = curve_vertex_smoothness(curve_n)
            return s, curve_smoothness_overall(curve_n, s)

        s_v, (s_overall, s_count) = stages.run("curve smoothness", _smooth, curve_n)
        ev.curve = CurveLocal(
            curve=curve_obj,
            samples=norm.invert(samples.points),
            sample_edge=samples.edge,
            sample_t=samples.t,
            sample_boundedness=beta_c,
            sample_centeredness_raw=c_raw_c,
            vertex_degree=curve_obj.degrees(),
            vertex_smoothness=s_v,
            smoothness_overall=float(s_overall),
            smoothness_count=int(s_count),
        )
    ev.timings = dict(stages.timings)
    ev.timings["total"] = time.perf_counter() - t_start
    return ev
