"""Orchestration: normalize, find the correspondence, run each metric, the trust checks, coverage
and the reference comparison; map progress, honour cancel, time each stage."""

from __future__ import annotations

import threading
import time
from typing import Callable

import numpy as np

from .correspondence import aggregate_rows, densify_curve, project_onto_curve, reverse_projection
from .curve import CurveSkeleton
from .curve_sampling import sample_curve
from .errors import Cancelled, SkelInputError
from .geometry import Normalization, as_points
from .metrics.boundedness import boundedness
from .metrics.centeredness import curve_centeredness, skeletal_centeredness
from .metrics.coverage import coverage, coverage_tau
from .metrics.reference import compare_with_reference
from .metrics.smoothness import curve_smoothness_overall, curve_vertex_smoothness, skeletal_smoothness
from .metrics.topology import topological_similarity
from .parallel import GraphTask, run_graph
from .params import Params
from .evaluation import CurveLocal, Evaluation, SkeletalLocal
from .trust import frame_fit_warning, frame_warnings, no_correspondence_warning, smoothness_warning

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
    "correspondence": 0.3,
    "skeletal coverage": 0.3,
    "curve coverage": 0.3,
    "reference": 0.1,
}

#: ``correspondence=`` choices of :func:`evaluate`
CORRESPONDENCE_CHOICES = ("auto", "reverse")


class _Stages:
    """Turns per-stage fractions into one overall fraction; checks ``cancel`` at every call.

    Stages may run side by side on several threads (:func:`skelcore.parallel.run_graph`): the caller's
    ``progress`` is called under a lock (never from two threads at once) with the weighted sum of every
    stage's fraction, and once :meth:`abort` has been called (a stage failed or was cancelled) every
    checkpoint raises, so the stages beside it stop too."""

    def __init__(self, names: list[str], progress: Progress | None, cancel: Callable[[], bool] | None):
        total = sum(_WEIGHTS[n] for n in names) or 1.0
        self._size = {n: _WEIGHTS[n] / total for n in names}
        self._done = {n: 0.0 for n in names}
        self._progress = progress
        self._cancel = cancel
        self._aborted = threading.Event()
        self._lock = threading.Lock()
        self._last = -1.0
        self._last_stage = ""
        self.timings: dict[str, float] = {}

    def abort(self) -> None:
        self._aborted.set()

    def _stop_if_asked(self, stage: str) -> None:
        if self._aborted.is_set() or (self._cancel is not None and self._cancel()):
            raise Cancelled(f"cancelled during {stage}")

    def checkpoint(self, stage: str) -> Callable[[float], None]:
        def check(fraction: float) -> None:
            self._stop_if_asked(stage)
            if self._progress is not None:
                with self._lock:
                    self._stop_if_asked(stage)  # a stage beside may have been cancelled while this one waited
                    self._done[stage] = max(self._done[stage], min(max(fraction, 0.0), 1.0))
                    overall = sum(self._size[n] * f for n, f in self._done.items())
                    # throttled (Orange3's habit), but a new stage is shown at once: the label names
                    # the stage that reported last
                    if stage != self._last_stage or overall - self._last >= 0.005 or fraction >= 1.0:
                        overall = max(overall, self._last)  # never back by a rounding error
                        self._last = overall
                        self._last_stage = stage
                        self._progress(overall, stage)

        return check

    def between(self, what: str) -> Callable[[float], None]:
        """A checkpoint for work between stages (the trust checks): cancel only, no progress."""

        def check(_fraction: float) -> None:
            if self._cancel is not None and self._cancel():
                raise Cancelled(f"cancelled during {what}")

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
    correspondence: str = "auto",
    reference_curve: CurveSkeleton | tuple | None = None,
    inputs: dict | None = None,
    workers: int | None = None,
) -> Evaluation:
    """Score a skeleton against its point cloud with the paper's four metrics (SPEC.md), the trust
    checks, SkelScope's coverage and, given a ``reference_curve``, the comparison with it.

    Parameters
    ----------
    cloud : (N_o, 3) original cloud, user units.
    skeletal : (N_s, 3) skeletal point set. Row i is where cloud row i went when N_s = N_o
        ("pointwise"), or ``skeletal_index`` maps skeletal rows to cloud rows ("index"); otherwise
        ``correspondence="reverse"`` maps every cloud point to its nearest skeletal point, and
        without either topology and skeletal centeredness are not computed ("none", a warning).
    curve : a :class:`CurveSkeleton` or a ``(vertices, edges)`` pair. With ``correspondence=
        "reverse"`` and no skeletal set, the cloud's projections onto its edges are scored as the
        skeletal set (topology, skeletal-style centeredness).
    reference_curve : a ground-truth curve in the cloud's frame (needs ``curve``).
    progress : ``progress(fraction, stage)``, called at checkpoints (throttled).
    cancel : returning True makes the next checkpoint raise :class:`Cancelled` (in whichever stage checks
        first when several run side by side).
    workers : threads running the independent stages side by side (None = all cores; 1 = one after the
        other, in the order they are started: the skeletal boundedness first, the curve's last); the
        values do not depend on it.

    Examples
    --------
    >>> ev = evaluate(cloud, skeletal=contracted)          # doctest: +SKIP
    >>> ev.summary()["boundedness"]["skeletal"]            # doctest: +SKIP
    """
    t_start = time.perf_counter()
    if correspondence not in CORRESPONDENCE_CHOICES:
        raise SkelInputError(f"correspondence must be one of {', '.join(CORRESPONDENCE_CHOICES)}, got {correspondence!r}")
    cloud = as_points("cloud", cloud)
    if len(cloud) < 2:
        raise SkelInputError("cloud: at least 2 points are needed")
    try:
        norm = Normalization.from_cloud(cloud, params.normalize_by, params.normalized_size)
    except ValueError:
        raise SkelInputError("cloud: all points coincide") from None
    cloud_n = norm.apply(cloud)

    skel = skel_n = None
    index = None
    mode: str | None = None
    if skeletal is not None:
        skel = as_points("skeletal point set", skeletal)
        skel_n = norm.apply(skel)
        if correspondence == "reverse":
            if skeletal_index is not None:
                raise SkelInputError("give either a skeletal index or reverse correspondence, not both")
            mode = "reverse"
        elif skeletal_index is not None:
            index = _check_index(skeletal_index, len(skel), len(cloud))
            mode = "index"
        else:
            mode = "pointwise" if len(skel) == len(cloud) else "none"
    elif skeletal_index is not None:
        raise SkelInputError("a skeletal index needs a skeletal point set")

    curve_obj: CurveSkeleton | None = None
    if curve is not None:
        curve_obj = CurveSkeleton.coerce(curve, "curve")
    if correspondence == "reverse" and skel is None:
        if curve_obj is None:
            raise SkelInputError("reverse correspondence needs a skeletal point set or a curve skeleton")
        mode = "reverse"
    ref_obj: CurveSkeleton | None = None
    if reference_curve is not None:
        if curve_obj is None:
            raise SkelInputError("a reference curve is compared with a curve skeleton: give one")
        ref_obj = CurveSkeleton.coerce(reference_curve, "reference curve")

    names: list[str] = []
    skeletal_from_curve = skel is None and mode == "reverse"
    skeletal_stages = ["skeletal boundedness", "skeletal smoothness"]
    if mode != "none":
        skeletal_stages = ["topology", "skeletal boundedness", "skeletal centeredness", "skeletal smoothness"]
    if mode == "reverse":
        skeletal_stages.insert(0, "correspondence")
    if skel is not None:
        names += skeletal_stages
    if curve_obj is not None:
        names += ["curve boundedness", "curve centeredness", "curve smoothness"]
    if skeletal_from_curve:
        names += skeletal_stages
    # SkelScope's coverage (not a paper metric) is exact and grows about as N^1.4 on tubes
    with_coverage = len(cloud) <= int(params.coverage_max_points)
    if skel is not None and with_coverage:
        names.append("skeletal coverage")
    if curve_obj is not None and with_coverage:
        names.append("curve coverage")
    if ref_obj is not None:
        names.append("reference")
    stages = _Stages(names, progress, cancel)
    p = params

    ev = Evaluation(params=p, normalization=norm, cloud=cloud, inputs=dict(inputs or {}), correspondence=mode)
    curve_n = samples = None
    if curve_obj is not None:
        curve_n = curve_obj.transformed(norm.apply)
        samples = sample_curve(curve_n, p.curve_samples, collinear_cos=p.collinear_cos)

    # The stages are independent (but for the correspondence): they run side by side on the cores, the
    # longest first so that the other thread takes the rest beside it (docs/performance.md 8).  ``got``
    # holds each result as soon as its stage is done.
    got: dict = {}

    def task(stage: str, fn, *args, after: tuple[str, ...] = (), **kwargs) -> GraphTask:
        def run() -> object:
            got[stage] = stages.run(stage, fn, *args, **kwargs)
            return got[stage]

        return GraphTask(stage, run, after)

    # the order they are started in: longest first (list scheduling); the curve's boundedness last when
    # the skeletal set's runs (on the hammer it is a quarter of it; put second, it held the other thread
    # while the rest waited), first without it
    first: list[GraphTask] = []
    rest: list[GraphTask] = []
    last: list[GraphTask] = []
    if skel is not None:
        _skeletal_tasks(task, first, rest, cloud_n, lambda: skel_n, lambda: got["correspondence"], mode, index, p,
                        after=())
        if mode == "reverse":
            rest.insert(0, task("correspondence", lambda checkpoint: reverse_projection(cloud_n, skel_n)))
    if curve_obj is not None:
        (last if skel is not None else first).append(
            task("curve boundedness", boundedness, cloud_n, samples.points, params=p))
        rest.append(task("curve centeredness", curve_centeredness, cloud_n, samples.points, samples.directions,
                         params=p))

        def _smooth(curve_n: CurveSkeleton, checkpoint) -> tuple:
            s = curve_vertex_smoothness(curve_n)
            return s, curve_smoothness_overall(curve_n, s)

        rest.append(task("curve smoothness", _smooth, curve_n))
        if skeletal_from_curve:
            rest.insert(0, task("correspondence", lambda checkpoint: project_onto_curve(cloud_n, curve_n)[0]))
            _skeletal_tasks(task, first, rest, cloud_n, lambda: got["correspondence"], lambda: None, "pointwise",
                            None, p, after=("correspondence",))
    # SkelScope's coverage (docs/metrics.md): tau (the cloud's spacing, one kNN pass) is computed inside
    # the first coverage stage that runs, so a cancel is seen during it too
    tau_box: list[float] = []
    tau_lock = threading.Lock()

    def _tau(checkpoint) -> float:
        with tau_lock:
            if not tau_box:
                tau_box.append(coverage_tau(cloud_n, p, checkpoint))
            return tau_box[0]

    if not with_coverage and (skel is not None or curve_n is not None):
        ev.not_computed["coverage"] = (
            f"the cloud has {len(cloud):,} points, above coverage_max_points = {int(p.coverage_max_points):,} "
            "(exact coverage of a skeletal set takes 15-45 s at 1M points on tube-like shapes; raise it with "
            "--set coverage_max_points=N)"
        )
    if skel is not None and with_coverage:
        def _skel_cov(checkpoint):
            tau = _tau(lambda f: checkpoint(0.1 * f))
            return coverage(cloud_n, skel_n, p, tau, checkpoint=lambda f: checkpoint(0.1 + 0.9 * f))

        rest.append(task("skeletal coverage", _skel_cov))
    if curve_n is not None and with_coverage:
        def _curve_cov(checkpoint):
            tau = _tau(lambda f: checkpoint(0.1 * f))
            step = max(tau / p.coverage_tau_factor, float(curve_n.edge_lengths().sum()) / 200_000)
            pts, _ = densify_curve(curve_n, step)
            return coverage(cloud_n, np.vstack([pts, curve_n.vertices]), p, tau,
                            checkpoint=lambda f: checkpoint(0.1 + 0.9 * f))

        rest.append(task("curve coverage", _curve_cov))
    if ref_obj is not None:
        ref_n = ref_obj.transformed(norm.apply)
        rest.append(task("reference", lambda checkpoint: compare_with_reference(curve_n, ref_n, _tau(checkpoint))))
    run_graph(first + rest + last, workers, on_error=stages.abort)

    if skel is not None:
        ev.skeletal = _skeletal_result(ev, got, skel, mode, index)
    if curve_obj is not None:
        s_v, (s_overall, s_count) = got["curve smoothness"]
        ev.curve = CurveLocal(
            curve=curve_obj,
            samples=norm.invert(samples.points),
            sample_edge=samples.edge,
            sample_t=samples.t,
            sample_boundedness=got["curve boundedness"],
            sample_centeredness_raw=got["curve centeredness"],
            vertex_degree=curve_obj.degrees(),
            vertex_smoothness=s_v,
            smoothness_overall=float(s_overall),
            smoothness_count=int(s_count),
        )
        if skeletal_from_curve:
            q_n = got["correspondence"]
            ev.skeletal = _skeletal_result(ev, got, norm.invert(q_n), "pointwise", None)
            ev.skeletal.source = "curve"
    ev.coverage_skeletal = got.get("skeletal coverage")
    ev.coverage_curve = got.get("curve coverage")
    ev.reference = got.get("reference")

    # ---- trust checks, coverage, reference (SkelScope's own; docs/metrics.md) ----------------
    between = stages.between("trust checks")  # only the rare frame-fit re-runs of boundedness

    def bounded_fraction(points_user: np.ndarray) -> float:
        beta = boundedness(cloud_n, norm.apply(points_user), params=p, checkpoint=between)
        return float(np.mean(beta > p.beta_star))

    if skel is not None:
        found = frame_warnings(cloud, skel, "skeletal point set", p)
        if not found:
            now = float(np.mean(ev.skeletal.boundedness > p.beta_star))
            found = frame_fit_warning(cloud, skel, now, bounded_fraction, "skeletal point set", p)
        ev.warnings += found
    if curve_obj is not None:
        found = frame_warnings(cloud, curve_obj.vertices, "curve skeleton", p)
        if not found:
            now = float(np.mean(ev.curve.sample_boundedness > p.beta_star))
            found = frame_fit_warning(cloud, ev.curve.samples, now, bounded_fraction, "curve skeleton", p)
        ev.warnings += found
        ev.warnings += smoothness_warning(ev.curve.vertex_degree)
    if mode == "none":
        ev.warnings.append(no_correspondence_warning(len(skel), len(cloud)))
    ev.timings = dict(stages.timings)
    ev.timings["total"] = time.perf_counter() - t_start
    return ev


def _check_index(skeletal_index: np.ndarray, n_skel: int, n_cloud: int) -> np.ndarray:
    index = np.asarray(skeletal_index)
    if index.dtype.kind not in "iu":
        if index.dtype.kind != "f" or not np.all(np.isfinite(index)) or np.any(index != np.round(index)):
            raise SkelInputError("skeletal index: cloud rows must be whole numbers")
    index = index.astype(np.int64).ravel()
    if index.shape != (n_skel,):
        raise SkelInputError(f"skeletal index: has {len(index)} rows, needs one cloud row per skeletal point ({n_skel})")
    if len(index) and (index.min() < 0 or index.max() >= n_cloud):
        bad = int(index.min()) if index.min() < 0 else int(index.max())
        raise SkelInputError(f"skeletal index: cloud row {bad} out of range (the cloud has {n_cloud} rows, 0-based)")
    return index


def _skeletal_tasks(task, first: list, rest: list, cloud_n, skel_of: Callable[[], np.ndarray],
                    rows_of: Callable[[], np.ndarray], mode, index, p, after: tuple[str, ...]) -> None:
    """The skeletal column's stages under each correspondence (pointwise, index, reverse, none), as tasks:
    boundedness into ``first``, the others into ``rest``.  ``skel_of()`` gives the normalized skeletal set
    once the tasks named in ``after`` are done (the curve's projections are computed by one of them),
    ``rows_of()`` the reverse correspondence's rows once its stage is done."""
    with_rows = after + (("correspondence",) if mode == "reverse" else ())
    first.append(task("skeletal boundedness", lambda checkpoint: boundedness(cloud_n, skel_of(), params=p,
                                                                               checkpoint=checkpoint), after=after))
    if mode != "none":
        def _topology(checkpoint):
            pointwise = skel_of()[rows_of()] if mode == "reverse" else skel_of()
            return topological_similarity(cloud_n, pointwise, params=p, checkpoint=checkpoint)

        rest.append(task("topology", _topology, after=with_rows))

        def _centeredness(checkpoint):
            if mode == "reverse":
                return skeletal_centeredness(cloud_n, skel_of()[rows_of()], params=p, checkpoint=checkpoint)
            corr_cloud = cloud_n if index is None else cloud_n[index]
            return skeletal_centeredness(corr_cloud, skel_of(), params=p, checkpoint=checkpoint)

        rest.append(task("skeletal centeredness", _centeredness, after=with_rows))
    rest.append(task("skeletal smoothness", lambda checkpoint: skeletal_smoothness(skel_of(), params=p,
                                                                                     checkpoint=checkpoint), after=after))


def _skeletal_result(ev, got: dict, skel, mode, index) -> SkeletalLocal:
    """The skeletal column from its stages' results (``got``, by stage name)."""
    rows = got.get("correspondence") if mode == "reverse" else None
    c_rows = None
    if mode == "none":
        reason = (f"the skeletal set has {len(skel)} points and the cloud {len(ev.cloud)}; "
                  "give a skeletal index or use reverse correspondence")
        ev.not_computed = {"topology": reason, "skeletal centeredness": reason}
        c_raw = np.full(len(skel), np.nan)
    else:
        ev.topology = got["topology"]
        if mode == "reverse":
            c_rows = got["skeletal centeredness"]
            c_raw = aggregate_rows(c_rows, rows, len(skel))
        else:
            c_raw = got["skeletal centeredness"]
    return SkeletalLocal(
        points=skel, boundedness=got["skeletal boundedness"], centeredness_raw=c_raw,
        smoothness=got["skeletal smoothness"], rows=rows, centeredness_rows_raw=c_rows,
        centeredness_available=mode != "none", index=index,
    )  # fmt: skip
