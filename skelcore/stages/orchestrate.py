"""``evaluate``: check the inputs and build the context, select the stages that apply from the
catalogue, run them side by side (:func:`skelcore.parallel.run_graph`) under one progress bar and one
cancel, assemble the Evaluation, run the trust checks, time each stage."""

from __future__ import annotations

import time
from typing import Callable

import numpy as np

from ..curve import CurveSkeleton
from ..evaluation import Evaluation
from ..parallel import GraphTask, run_graph
from ..params import Params
from .assemble import assemble, diagnostics_of, diagnostics_warnings, trust_warnings
from .catalogue import Stage, select, start_order
from .context import EvalContext, build_context
from .evaluation_source import EvaluationSource
from .progress import Progress, StageProgress

__all__ = ["evaluate", "finish"]


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
    reference_radius: np.ndarray | None = None,
    reference_outside: np.ndarray | None = None,
    inputs: dict | None = None,
    workers: int | None = None,
    viewpoints=None,
    remove_outliers: bool = False,
    cap_openings: bool = False,
    on_stages: Callable[[tuple[str, ...]], None] | None = None,
) -> Evaluation:
    """Score a skeleton against its point cloud with the paper's four metrics (docs/metrics.md), the trust
    checks, SkelScope's coverage and, given a ``reference_curve``, the comparison with it.

    Parameters
    ----------
    cloud : (N_o, 3) array
        The original cloud, in the user's units (normalized inside, docs/metrics.md 0).
    skeletal : (N_s, 3) array, optional
        The skeletal point set. Row i is where cloud row i went when N_s = N_o ("pointwise"), or
        ``skeletal_index`` maps skeletal rows to cloud rows ("index"); otherwise
        ``correspondence="reverse"`` maps every cloud point to its nearest skeletal point, and
        without either, topology and skeletal centeredness are not computed ("none", a warning;
        docs/metrics.md 5.1).
    curve : CurveSkeleton or (vertices, edges), optional
        The curve skeleton. With ``correspondence="reverse"`` and no skeletal set, the cloud's
        projections onto its edges are scored as the skeletal set (topology, skeletal-style
        centeredness).
    params : Params
        Every constant of docs/metrics.md (thresholds, neighbour counts, estimator).
    progress : callable, optional
        ``progress(fraction, stage)``, called at checkpoints (throttled).
    cancel : callable, optional
        Returning True makes the next checkpoint raise :class:`~skelcore.Cancelled` (in whichever
        stage checks first when several run side by side).
    skeletal_index : (N_s,) int array, optional
        The cloud row each skeletal point corresponds to (the "index" mode of docs/metrics.md 5.1).
    correspondence : {"auto", "pointwise", "index", "reverse", "none"}
        How skeletal points map to cloud points (docs/metrics.md 5.1); "auto" picks from the inputs.
    reference_curve : CurveSkeleton or (vertices, edges), optional
        A ground-truth curve in the cloud's frame (needs ``curve``; docs/metrics.md 5.3): the reference comparison
        (``Evaluation.reference``) and the ground-truth metrics (``Evaluation.ground_truth``,
        docs/metrics.md 5.3.1) in the cloud's units.
    reference_radius : (V,) array, optional
        The reference's radius per vertex (the cloud's units); default its own (``CurveSkeleton.radius``,
        read from PLY ``radius``, SWC, ...); where unknown, estimated from the cloud.
    reference_outside : (V,) array, optional
        How far each reference vertex lies outside the surface the cloud was drawn from, in its radii
        (0: inside; a real suite's facts): the ground truth adds its held scores (docs/metrics.md 5.3.1).
    inputs : dict, optional
        Free-form description of the inputs (file names), kept in the JSON document.
    workers : int, optional
        Threads running the independent stages side by side (None = all cores; 1 = one after the
        other); the values do not depend on it.
    viewpoints : array of x y z, optional
        The sensors' positions of a scan seen from some sides only: boundedness counts the directions
        seen from them, skeletal centeredness leaves out the viewing depth (docs/metrics.md 6.3;
        SkelScope's extension, None = the paper's).
    remove_outliers : bool
        Evaluate without the cloud's stray points (and their skeletal rows); they are found and
        reported in any case (the ``outliers`` warning, docs/metrics.md 6.4).
    cap_openings : bool
        Close the cloud's small flat openings with points on their planes for boundedness, as the
        paper did for its cave (docs/metrics.md 6.2).
    on_stages : callable, optional
        ``on_stages(names)`` whenever the set of stages running side by side changes (their names in
        the order they started; empty between stages), e.g. for a label naming them all.

    Returns
    -------
    Evaluation
        Every local value, the overall scores (:meth:`Evaluation.summary`), warnings and diagnostics.

    Examples
    --------
    >>> ev = evaluate(cloud, skeletal=contracted)          # doctest: +SKIP
    >>> ev.summary()["boundedness"]["skeletal"]            # doctest: +SKIP
    """
    t_start = time.perf_counter()
    args = dict(cloud=cloud, skeletal=skeletal, curve=curve, params=params, skeletal_index=skeletal_index,
                correspondence=correspondence, reference_curve=reference_curve, reference_radius=reference_radius,
                reference_outside=reference_outside, inputs=inputs, workers=workers, viewpoints=viewpoints,
                remove_outliers=remove_outliers, cap_openings=cap_openings)
    ctx = build_context(cloud, skeletal, curve, params, skeletal_index=skeletal_index,
                        correspondence=correspondence, reference_curve=reference_curve,
                        reference_radius=reference_radius, reference_outside=reference_outside,
                        viewpoints=viewpoints,
                        remove_outliers=remove_outliers, cap_openings=cap_openings,
                        checkpoint=StageProgress({}, None, cancel).between("scan preparation"))
    stages = select(ctx)
    tracker = StageProgress({s.name: s.weight for s in stages}, progress, cancel, on_stages)
    names = {s.name for s in stages}
    tasks = [_task(stage, ctx, tracker, names) for stage in start_order(stages, ctx)]
    run_graph(tasks, workers, on_error=tracker.abort)
    ev = finish(ctx, inputs, tracker.between("trust checks"))
    ev.timings = dict(tracker.timings)
    ev.timings["total"] = time.perf_counter() - t_start
    ev.source = EvaluationSource(args=args, ctx=ctx)
    return ev


def finish(ctx: EvalContext, inputs: dict | None, checkpoint: Callable[[float], None], scan: bool = True
           ) -> Evaluation:
    """The Evaluation of ``ctx`` once its stages are done: assembled, with the trust checks and the
    diagnostics' warnings (an edited curve's update finishes the same way; ``scan`` False: without the
    real-scan checks, :func:`.assemble.trust_warnings`)."""
    ev = assemble(ctx, inputs)
    ev.warnings += trust_warnings(ctx, ev, checkpoint, scan)
    codes = {w.code for w in ev.warnings}
    ran = _defect_checks(ctx)
    if "frame" in codes:  # in another frame, every diagnostic would say so too
        ev.not_computed.update(dict.fromkeys(
            ran, "the skeleton seems to be in another frame than the cloud (warning frame): its defects are not judged"))
    else:
        if "open_surface" in codes:
            _every_ball_explains(ctx, ev)
        found = diagnostics_warnings(ctx)
        skipped: dict[str, str] = {}
        if "open_surface" in codes or ctx.viewpoints_n is not None:
            # the cycle test voxelizes the shape's interior, which an open scan does not enclose
            why = ("the cloud is not a closed surface (warning open_surface)" if "open_surface" in codes
                   else "the scan is seen from given viewpoints")
            skipped.update(dict.fromkeys(("spurious_cycles", "missing_cycles"),
                                         f"{why}: the shape's interior, which the cycle test voxelizes, is not enclosed"))
        if "open_surface" in codes:
            # and the outside test reads the paper's boundedness, which rays leaving through the openings
            # defeat: on the true axis of a half cylinder it fired (with viewpoints it reads what was seen)
            skipped["outside"] = ("the cloud is not a closed surface (warning open_surface): rays leave through "
                                  "its openings, so boundedness cannot tell outside from inside; only the branches "
                                  f"reaching more than outside_reach = {ctx.params.outside_reach:g} local radii out "
                                  "were looked for")
        skipped = {k: v for k, v in skipped.items() if k in ran}
        ev.not_computed.update(skipped)
        ev.warnings += [w for w in found if w.code not in skipped]
        defects = ctx.results.get("curve defects")
        if "outside" in skipped and defects is not None:  # the reach test needs no boundedness
            ev.warnings += defects.outside.warnings(reach_only=True)
        elif defects is not None and defects.outside.unchecked:  # voxels too coarse: its warnings are the reach test's
            ev.not_computed["outside"] = defects.outside.unchecked
        if defects is not None and defects.spurs.unchecked:  # twigs the cloud cannot show: not judged
            ev.not_computed["spurious_branches"] = defects.spurs.unchecked
        if defects is not None and defects.surface.unchecked:  # a slab thicker than the parts: not judged
            ev.not_computed["along_surface"] = defects.surface.unchecked
    return ev


def _every_ball_explains(ctx: EvalContext, ev: Evaluation) -> None:
    """On an open surface the voxelized interior is not enclosed: when some elements were left out as
    outside, the missing parts are found again leaving out only those in no solid voxel whose nearest
    cloud points lie on one side (``outside_one_sided``; a half cylinder's axis sees a half ring, 2 / pi;
    docs/diagnostics.md "Completeness")."""
    from ..diagnostics.missing_parts import missing_parts
    from ..diagnostics.outside import one_sided

    def inside(points: np.ndarray) -> np.ndarray:
        shape = ctx.interior()
        ijk = shape.index_of(points)
        solid = shape.solid()[ijk[:, 0], ijk[:, 1], ijk[:, 2]]
        if solid.all():
            return solid
        solid[~solid] = ~one_sided(ctx.diag_tree(), points[~solid], ctx.params.outside_one_sided)
        return solid

    redone = False
    for kind in ("skeletal", "curve"):
        found = ctx.results.get(f"{kind} missing parts")
        if found is None or not found.outside_elements:
            continue
        cov = ctx.results.get(f"{kind} coverage")
        ctx.results[f"{kind} missing parts"] = missing_parts(
            ctx.cloud_n, ctx.skeletal_n if kind == "skeletal" else ctx.curve_n, ctx.params, cov=cov,
            tau=None if cov is None else cov.tau, what=found.what, to_user=ctx.norm.invert, inside=inside,
            chords=ctx.chords)
        redone = True
    if redone:
        ev.diagnostics = diagnostics_of(ctx)


def _defect_checks(ctx: EvalContext) -> list[str]:
    """The defect warnings whose checks ran (docs/diagnostics.md): what a switched-off check names in
    ``not_computed``."""
    got = ctx.results
    out: list[str] = []
    if "skeletal missing parts" in got or "curve missing parts" in got:
        out.append("incomplete")
    if "curve defects" in got:
        out += ["spurious_branches", "spurious_cycles", "missing_cycles", "disconnected", "along_surface"]
    if "curve defects" in got or "skeletal outside" in got:
        out.append("outside")
    return out


def _task(stage: Stage, ctx: EvalContext, tracker: StageProgress, names: set[str]) -> GraphTask:
    """The stage as a graph task: its result lands in ``ctx.results`` as soon as it is done; it starts
    after the selected stages it waits for."""

    def run() -> object:
        ctx.results[stage.name] = tracker.run(stage.name, stage.fn, ctx)
        return ctx.results[stage.name]

    return GraphTask(stage.name, run, tuple(a for a in stage.waits(ctx) if a in names))
