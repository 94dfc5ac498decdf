"""The Evaluation of an edited curve skeleton (:meth:`skelcore.Evaluation.update`), equal to evaluating
it afresh with the same cloud, skeletal set and params, but reusing what an edit cannot change: every
stage that does not read the curve (the skeletal column, topology, stray points, the cloud's trees and
interior), and each curve sample's boundedness and centeredness when a sample at the same position (and
direction) was scored before. That is exact because each sample's value depends only on its position,
direction, the cloud and the params: with the toolbox sampling an edit moves the samples of the edges
whose length share or numbering changed, and those are scored again. Boundedness is reused only when
the rays estimator scores every sample on its own (no far field shared between samples). Evaluations
with a scan option, or whose skeletal column is the curve's projection, are evaluated again.
:func:`complete_update` adds the curve's diagnostics to an update that left them out (a viewer's
second phase), the two together equal to one update."""

from __future__ import annotations

import os
import threading
import time
from itertools import repeat
from dataclasses import replace
from typing import Any, Callable

import numpy as np

from ..curve import CurveSkeleton
from ..diagnostics.spur_cache import NearestByBalls
from ..errors import Cancelled, SkelInputError
from ..evaluation import Evaluation
from ..geometry import check_magnitude, no_checkpoint, unique_rows
from ..metrics.ball_tree import BallTree
from ..metrics.boundedness import LoneRays, in_raster_frame, rays_plan_is_exact
from ..metrics.ray_hints import merged_tables
from ..metrics.centeredness import curve_centeredness, slab_grid
from ..metrics.curve_sampling import sample_curve
from ..parallel import GraphTask, run_graph
from ..stages.catalogue import CATALOGUE, Stage, start_order
from ..stages.context import EvalContext
from ..stages.evaluation_source import CURVE_STAGES, EvaluationSource
from ..stages.orchestrate import evaluate, finish
from .change import Change
from .coverage_update import carry_memo, curve_coverage, link_contexts, parent_of
from .missing_update import curve_missing_parts

__all__ = ["update_evaluation", "complete_update", "left_out", "CURVE_STAGES", "DIAGNOSTIC_STAGES"]

#: left out by ``update(diagnostics=False)``
DIAGNOSTIC_STAGES = ("curve coverage", "curve defects", "curve missing parts")
_GRID_LOCK = threading.Lock()  # one slab grid per cache, even when two updates run at once
_TREE_LOCK = threading.Lock()  # one ball tree of the diagnostics' points per evaluation
_PLAN_LOCK = threading.Lock()  # the kept plans' flags, read and trimmed by updates side by side
LEFT_OUT = "left out by Evaluation.update(diagnostics=False)"
#: the fewest moved samples per call of the rays kernel while the other stages run (each sample is scored
#: on its own: the same bits in any grouping; each call's streams start without hints, docs/boundedness.md 3.9)
_RAYS_CHUNK = 10


def update_evaluation(ev: Evaluation, edited: Change | CurveSkeleton | Any, *, diagnostics: bool = True,
                      scan_checks: bool = True) -> Evaluation:
    """``ev``'s evaluation of the edited curve (a Change, or the new curve in any form
    :meth:`CurveSkeleton.coerce` takes); ``scan_checks`` False with ``diagnostics`` False: without the
    real-scan trust checks (:meth:`Evaluation.update`), which :func:`complete_update` runs."""
    t0 = time.perf_counter()
    curve = edited.curve if isinstance(edited, Change) else CurveSkeleton.coerce(edited, "edited curve")
    if curve is None:
        raise SkelInputError("this change carries no edited curve")
    src = ev.source
    if not isinstance(src, EvaluationSource):
        raise SkelInputError("this Evaluation keeps no record of its inputs (it was not made by evaluate): "
                             "evaluate the edited curve instead")
    if src.args.get("curve") is None:
        raise SkelInputError("update() scores an edited curve skeleton: this Evaluation has none")
    args = dict(src.args, curve=curve)
    old = src.ctx
    if old is None or old.scan is not None or old.viewpoints_n is not None or old.from_curve:
        new = evaluate(**args)
        new.source.cache = src.cache
        return new
    check_magnitude("curve skeleton", curve.vertices)
    ctx = _edited_context(old, curve, src.cache)
    link_contexts(src.cache, ctx, old)
    run_graph(_tasks(old, ctx, src.cache, diagnostics, args.get("workers")), args.get("workers"))
    out = finish(ctx, args.get("inputs"), no_checkpoint, scan=scan_checks or diagnostics)
    out.timings = {"update": time.perf_counter() - t0}
    results = dict(ctx.results)
    out.source = EvaluationSource(args=args, ctx=ctx, cache=src.cache)
    if left_out(out):  # what the source drops, kept until complete_update has finished it again
        out.source.rest = {k: v for k, v in results.items() if k not in ctx.results}
    return out


def left_out(ev: Evaluation) -> tuple[str, ...]:
    """The curve's stages ``update(diagnostics=False)`` left out of ``ev`` (() when none)."""
    src = ev.source
    ctx = src.ctx if isinstance(src, EvaluationSource) else None
    return () if ctx is None else tuple(n for n in DIAGNOSTIC_STAGES if ctx.not_computed.get(n) == LEFT_OUT)


def complete_update(ev: Evaluation, cancel: Callable[[], bool] | None = None, scan_checks: bool = True) -> Evaluation:
    """``ev`` (an ``update(diagnostics=False)``) with the curve's coverage, defects and missing parts it
    left out: the Evaluation ``update(change)`` gives, ``ev`` itself unchanged (the second phase of an
    edit's scoring, docs/performance.md 6.10). ``cancel()`` True stops it at a stage's next checkpoint
    (:class:`Cancelled`). ``ev`` when nothing was left out. ``scan_checks`` False: without the
    real-scan trust checks (:meth:`Evaluation.update`)."""
    t0 = time.perf_counter()
    names = left_out(ev)
    if not names:
        if LEFT_OUT in ev.not_computed.values():  # a pickled first phase: its context is gone
            raise SkelInputError("this Evaluation keeps no record of its inputs (it was pickled): "
                                 "update or evaluate the edited curve with its diagnostics instead")
        return ev
    src = ev.source
    old = src.ctx
    unset = {k: v for k, v in old.not_computed.items() if k not in names}
    ctx = replace(old, results={**old.results, **src.rest}, not_computed=unset, unseen=dict(old.unseen))

    def checkpoint(_fraction: float = 0.0) -> None:
        if cancel is not None and cancel():
            raise Cancelled("the edited curve's defects were cancelled")

    stages = start_order([s for s in CATALOGUE if s.name in names and s.applies(ctx)], ctx)
    parent = parent_of(src.cache, old)
    if parent is not None:  # the completed update is edited from the same curve
        link_contexts(src.cache, ctx, parent)
    if "curve coverage" not in names:  # computed before (a first look): its memo serves the next edits
        carry_memo(src.cache, old, ctx)

    def task(stage: Stage) -> GraphTask:
        def run() -> object:
            checkpoint()
            if stage.name == "curve coverage":  # by difference from the curve edited (coverage_update)
                ctx.results[stage.name] = curve_coverage(ctx, parent, src.cache)
                return ctx.results[stage.name]
            if stage.name == "curve missing parts":  # the cloud's tree kept (missing_update)
                ctx.results[stage.name] = curve_missing_parts(ctx, src.cache, checkpoint, parent)
                return ctx.results[stage.name]
            ctx.results[stage.name] = stage.fn(ctx, checkpoint)
            return ctx.results[stage.name]

        return GraphTask(stage.name, run, tuple(a for a in stage.after(ctx) if a in names))

    run_graph([task(s) for s in stages], src.args.get("workers"))
    checkpoint()
    out = finish(ctx, src.args.get("inputs"), checkpoint, scan=scan_checks)
    out.timings = {"update": ev.timings.get("update", 0.0) + time.perf_counter() - t0,
                   "diagnostics": time.perf_counter() - t0}
    out.source = EvaluationSource(args=src.args, ctx=ctx, cache=src.cache)
    return out


def compute_left_out(ev: Evaluation, names: tuple[str, ...]) -> dict[str, Any] | None:
    """The stages ``names`` that ``ev`` (an ``update(diagnostics=False)``) left out, computed now in its
    context in that order and no longer left out, so that :func:`complete_update` adds only the others;
    their results by name. None when ``ev`` keeps no context or its last named stage was not left out
    or does not apply (a candidate's first look in repair, docs/repair.md "Never worse")."""
    ctx = getattr(ev.source, "ctx", None)
    by_name = {s.name: s for s in CATALOGUE}
    last = by_name[names[-1]]
    if ctx is None or not last.applies(ctx) or ctx.not_computed.get(last.name) != LEFT_OUT:
        return None
    done = {}
    parent = parent_of(ev.source.cache, ctx)
    for stage in (by_name[n] for n in names):
        if stage.applies(ctx):
            if stage.name == "curve coverage" and parent is not None:  # by difference (coverage_update)
                done[stage.name] = ctx.results[stage.name] = curve_coverage(ctx, parent, ev.source.cache)
            elif stage.name == "curve missing parts":
                done[stage.name] = ctx.results[stage.name] = curve_missing_parts(ctx, ev.source.cache, parent=parent)
            else:
                done[stage.name] = ctx.results[stage.name] = stage.fn(ctx, no_checkpoint)
            ctx.not_computed.pop(stage.name, None)
    return done


def _tasks(old: EvalContext, ctx: EvalContext, cache: dict[str, Any], diagnostics: bool,
           workers: int | None = None) -> list[GraphTask]:
    """The curve's stages as graph tasks, run side by side as :func:`evaluate` runs them (its start
    order: the curve's coverage beside the samples' scoring, the defects once the boundedness is in):
    the samples' boundedness and centeredness from the old values where they can be kept, the others
    computed again; ``diagnostics=False`` names the left-out ones in ``not_computed``; ``workers``:
    run_graph's (1: one lane, nothing runs beside the curve's boundedness)."""
    beside = threading.Event()  # set when the stages that run beside the curve's boundedness are done
    if int(workers or os.cpu_count() or 1) <= 1:
        beside.set()
    incremental = {"curve boundedness": lambda: _sample_boundedness(old, ctx, cache, beside),
                   "curve centeredness": lambda: _sample_centeredness(old, ctx, cache),
                   "curve coverage": lambda: curve_coverage(ctx, old, cache),
                   "curve missing parts": lambda: curve_missing_parts(ctx, cache, parent=old)}
    stages = []
    for stage in start_order([s for s in CATALOGUE if s.name in CURVE_STAGES and s.applies(ctx)], ctx):
        if not diagnostics and stage.name in DIAGNOSTIC_STAGES:
            ctx.not_computed[stage.name] = LEFT_OUT
        else:
            stages.append(stage)
    names = {s.name for s in stages}
    after = {s.name: tuple(a for a in s.after(ctx) if a in names) for s in stages}
    pending = {n for n in names if not _waits_for(n, "curve boundedness", after)}
    lock = threading.Lock()

    def done(name: str) -> None:
        with lock:
            pending.discard(name)
            if not pending:
                beside.set()

    def task(stage: Stage) -> GraphTask:
        fn = incremental.get(stage.name) or (lambda: stage.fn(ctx, no_checkpoint))

        def run() -> object:
            try:
                ctx.results[stage.name] = fn()
            finally:
                done(stage.name)
            return ctx.results[stage.name]

        return GraphTask(stage.name, run, after[stage.name])

    done("curve boundedness")  # not beside itself
    return [task(s) for s in stages]


def _waits_for(name: str, other: str, after: dict[str, tuple[str, ...]]) -> bool:
    """Whether task ``name`` is ``other`` or starts after it, directly or not."""
    return name == other or any(_waits_for(a, other, after) for a in after.get(name, ()))


def _edited_context(old: EvalContext, curve: CurveSkeleton, cache: dict[str, Any]) -> EvalContext:
    """``old`` with the edited curve and its samples, the results of the stages that read no curve kept
    (the cloud's trees and interior are shared)."""
    p = old.params
    curve_n = curve.transformed(old.norm.apply)
    samples = sample_curve(curve_n, p.curve_samples, collinear_cos=p.collinear_cos, method=p.curve_sampling)
    kept = {k: v for k, v in old.results.items() if k not in CURVE_STAGES}
    unset = {k: v for k, v in old.not_computed.items() if v != LEFT_OUT}  # an update of a first phase
    return replace(old, curve=curve, curve_n=curve_n, samples=samples, results=kept, not_computed=unset,
                   unseen=dict(old.unseen), spur_memo=old.spur_memo.next(), _diag_tree=_diag_tree(old, cache),
                   ray_hints=[])


def _diag_tree(old: EvalContext, cache: dict[str, Any]) -> list:
    """The diagnostics' tree for the edited curve: ``old``'s, whose one-nearest distances a ball tree
    of the same points gives (:class:`NearestByBalls`, the same bits; the curve's branch radii and the
    outside test's walk ask them from the axis): the cloud index's when the tree holds the whole cloud,
    else one of the subsample made once per evaluation (kept in ``cache``)."""
    tree = old._diag_tree[0] if old._diag_tree else None
    if tree is None or isinstance(tree, NearestByBalls):
        return old._diag_tree
    with _TREE_LOCK:
        kept = cache.get("diagnostics' nearest")
        if kept is None or kept.kd is not tree:
            if old.cloud_index is not None and tree.n == len(old.cloud_n) <= old.params.diag_max_points:
                kept = NearestByBalls(tree, old.cloud_index.surface)
            else:
                kept = NearestByBalls(tree, _balls_of(tree.data))
            cache["diagnostics' nearest"] = kept
    return [kept]


def _balls_of(points: np.ndarray) -> Callable[[], BallTree]:
    """A ball tree of ``points``, built at its first call (then kept)."""
    made: list = []
    lock = threading.Lock()

    def get() -> BallTree:
        with lock:
            if not made:
                made.append(BallTree(points, slab=True))
            return made[0]

    return get


def _keys(*columns: np.ndarray) -> list[bytes]:
    """Each row's bytes (the columns side by side as float64), from one view of the rows."""
    rows = np.ascontiguousarray(np.hstack(columns), dtype=np.float64)
    return rows.view(np.dtype((np.void, 8 * rows.shape[1]))).ravel().tolist()


def _reuse(old_keys: list[bytes], old_values: np.ndarray, new_keys: list[bytes]) -> tuple[np.ndarray, np.ndarray]:
    """(values, which are missing) for ``new_keys`` from the old (key, value) pairs."""
    known = dict(zip(old_keys, np.asarray(old_values, dtype=float).tolist()))
    values = np.array(list(map(known.get, new_keys, repeat(np.nan))), dtype=float)
    missing = ~np.fromiter(map(known.__contains__, new_keys), bool, len(new_keys))
    return values, missing


def _plan_is_exact(cloud: np.ndarray, samples: Any, params: Any, cache: dict[str, Any]) -> bool:
    """:func:`rays_plan_is_exact` of these samples, kept by their distinct positions (the plan is made
    of those alone, in lexicographic order, against the same cloud and params for every update of
    one evaluation): a deleted edge keeps every position, and at 1M points the plan takes 0.1 s."""
    key = np.ascontiguousarray(unique_rows(np.asarray(samples.points, dtype=float), no_checkpoint)[0]).tobytes()
    with _PLAN_LOCK:
        flag = cache.setdefault("exact plans", {}).get(key)
    if flag is None:
        flag = rays_plan_is_exact(cloud, samples.points, params)
        with _PLAN_LOCK:
            known = cache["exact plans"]
            known[key] = flag
            while len(known) > 8:  # the last few samplings (an undo comes back to one)
                known.pop(next(iter(known)))
    return flag


def _sample_boundedness(old: EvalContext, ctx: EvalContext, cache: dict[str, Any],
                        beside: threading.Event | None = None) -> np.ndarray:
    """Curve boundedness of the new samples: kept where a sample was scored before at the same place,
    when both samplings are scored pair by pair (else all again, as :func:`evaluate` would); the others'
    rays start from the hint tables the old samples nearby left, and the new curve's tables are kept in
    ``ctx.ray_hints`` (docs/boundedness.md 3.18). ``beside`` set: the stages that run beside it are done."""
    p, s_old, s_new = ctx.params, old.samples, ctx.samples
    cloud = ctx.bounded_cloud_n
    if not (_plan_is_exact(cloud, s_old, p, cache) and _plan_is_exact(cloud, s_new, p, cache)):
        return ctx.boundedness(s_new.points, keep=ctx.ray_hints)
    beta, todo = _reuse(_keys(s_old.points), old.results["curve boundedness"], _keys(s_new.points))
    rows = np.flatnonzero(todo)
    # the moved samples' rays start from the hits of the old samples nearby (docs/boundedness.md 3.18)
    seeds = old.ray_hints[0] if old.ray_hints else None
    made: list = []
    cast = LoneRays.of(cloud, ctx.bounded_params or p)  # every call's setup once (None: no rays, all 0)
    # while the other lane's stages hold their core, a third of the samples left in streams on the other
    # cores (one on two cores); once they are done (or few are left), the rest in one call on every core. In one call, its
    # second stream waited for the core those stages held and ran alone after them (a pruned branch's
    # 180 samples at 100k points); every call's streams start without hints (docs/performance.md 6.10)
    # the moved positions made distinct (and put in the raster frame) once, the seeds' nearest asked once
    # for all; each call casts its part's in lexicographic order, as a call of the part's rows would
    uniq, inverse, _ = unique_rows(s_new.points[rows], no_checkpoint)
    others = max(1, (os.cpu_count() or 1) - 1)
    beta[rows] = 0.0
    if cast is not None:
        q_r, seeds = cast.in_frame(uniq), cast.seeds(seeds)
        near = seeds.nearest(q_r) if seeds is not None and len(seeds) and len(q_r) else None
    lo = 0
    while cast is not None and lo < len(rows):
        left = len(rows) - lo
        alone = beside is not None and not beside.is_set() and left > 2 * _RAYS_CHUNK
        take = max(_RAYS_CHUNK, left // 3) if alone else left
        ids = np.unique(inverse[lo:lo + take])
        got = cast.distinct(q_r[ids], seeds=seeds, keep=made, workers=others if alone else None,
                            nearest=None if near is None else (near[0][ids], near[1][ids]))
        beta[rows[lo:lo + take]] = got[np.searchsorted(ids, inverse[lo:lo + take])]
        lo += take
    kept_at = in_raster_frame(s_new.points[~todo], cast.centre) if seeds is not None and cast is not None else None
    ctx.ray_hints[:] = [t for t in [merged_tables(seeds, made, kept_at)] if t is not None]
    return beta


def _sample_centeredness(old: EvalContext, ctx: EvalContext, cache: dict[str, Any]) -> np.ndarray:
    """Curve centeredness of the new samples: kept where a sample was scored before at the same place
    and direction."""
    p, s_old, s_new = ctx.params, old.samples, ctx.samples
    c, todo = _reuse(_keys(s_old.points, s_old.directions), old.results["curve centeredness"],
                     _keys(s_new.points, s_new.directions))
    if todo.any():
        with _GRID_LOCK:
            if "slab grid" not in cache:
                cache["slab grid"] = slab_grid(ctx.cloud_n, p)
        # one span on this thread: its fits are one batched call, and the rays kernel's threads and the
        # diagnostics already hold the other cores (180 samples of a prune: 0.14 -> 0.06 CPU s; the whole
        # update 0.41 -> 0.38 CPU s, docs/performance.md 6.10)
        span = int(todo.sum())
        c[todo] = curve_centeredness(ctx.cloud_n, s_new.points[todo], s_new.directions[todo], params=p,
                                     grid=cache["slab grid"], span=span)
    return c
