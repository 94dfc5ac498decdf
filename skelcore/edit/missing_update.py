"""The curve missing parts stage of an edit's update: the stage's own call
(:mod:`skelcore.stages.catalogue`), with the KD-tree of the points its regions ask about (the
normalized cloud or its kept subsample) kept from one update of an evaluation to the next, which
lets the regions take most neighbours from one search of it, and the coverage it computes itself
(no curve coverage, or elements in the air) by difference from the curve edited
(:mod:`skelcore.edit.coverage_update`; the same bits; docs/performance.md 6.10)."""

from __future__ import annotations

import threading
from types import SimpleNamespace
from typing import Any, Callable

import numpy as np
from scipy.spatial import cKDTree

from ..diagnostics.missing_parts import (SPREAD_CHUNK, MissingParts, coverage_elements, missing_parts,
                                         sampled_points)
from ..geometry import Checkpoint, no_checkpoint, query_workers, unique_rows
from ..metrics.cloud_index import CloudIndex
from ..metrics.coverage import Coverage
from ..params import Params
from .coverage_update import _memo, _store, coverage_from

__all__ = ["curve_missing_parts"]

#: skelcore.stages.context.EvalContext, not imported: the edits sit below the stages
EvalContext = Any
_LOCK = threading.Lock()
_KEY = "missing parts' cloud tree"
_NEAREST = "missing parts' nearest samples"
_NEIGHBOURS = "missing parts' kept neighbours"
_MEMOS = "missing parts' coverage memos"  # per curve: (the points' index, tau, CoverageMemo)
_SAMPLED = "missing parts' points"


def _cloud_tree(cache: dict[str, Any]) -> Callable[[np.ndarray], cKDTree]:
    """``cKDTree(points)``, kept in ``cache`` with those points: every update of one evaluation asks about
    the same array (its normalized cloud, or above ``missing_max_points`` the subsample that
    :func:`skelcore.metrics.cloud_index.kept_index` keeps); another array replaces it."""

    def get(points: np.ndarray) -> cKDTree:
        # the same memory, shape and strides (missing_parts asks through a new view of the same array);
        # the view kept holds that memory, so no other array can take its place
        key = (points.__array_interface__["data"][0], points.shape, points.strides, points.dtype.str)
        with _LOCK:
            kept = cache.get(_KEY)
            if kept is None or kept[0] != key:
                kept = (key, cKDTree(points), points)
                cache[_KEY] = kept
        return kept[1]

    return get


def _nearest_sample(cache: dict[str, Any], tree: Callable[[np.ndarray], cKDTree]
                    ) -> Callable[[np.ndarray, np.ndarray, Checkpoint], tuple[np.ndarray, np.ndarray]]:
    """Each cloud point's distance and row of its nearest point of the subsample (of ``tree``, the kept
    tree of those points), searched once for the same two arrays and kept in ``cache`` (12 bytes a
    cloud point): the missing parts' spread reads it at every update instead of searching 1M points."""

    def get(cloud: np.ndarray, pts: np.ndarray, checkpoint: Checkpoint) -> tuple[np.ndarray, np.ndarray]:
        key = tuple((a.__array_interface__["data"][0], a.shape, a.strides, a.dtype.str) for a in (cloud, pts))
        with _LOCK:
            kept = cache.get(_NEAREST)
        if kept is not None and kept[0] == key:
            return kept[1]
        search = tree(pts)
        d, j = np.empty(len(cloud)), np.empty(len(cloud), np.int32)
        for lo in range(0, len(cloud), SPREAD_CHUNK):  # a checkpoint between chunks, as the spread's
            checkpoint(lo / len(cloud))
            part = cloud[lo:lo + SPREAD_CHUNK]
            d[lo:lo + len(part)], j[lo:lo + len(part)] = search.query(part, workers=query_workers(len(part)))
        with _LOCK:  # the arrays kept hold that memory: no other array takes their place
            cache[_NEAREST] = (key, (d, j), cloud, pts)
        return d, j

    return get


def _sampled(cache: dict[str, Any]) -> Callable[[np.ndarray, Params], tuple[np.ndarray | None, CloudIndex,
                                                                           Callable[[Checkpoint], float]]]:
    """``missing_parts``' subsample, its index and its tau
    (:func:`skelcore.diagnostics.missing_parts.sampled_points`), kept in ``cache`` for the same cloud
    array (every update of one evaluation reads its normalized cloud) and params; the tau found at its
    first call."""

    def get(cloud: np.ndarray, p: Params) -> tuple[np.ndarray | None, CloudIndex, Callable[[Checkpoint], float]]:
        key = (cloud.__array_interface__["data"][0], cloud.shape, cloud.strides, cloud.dtype.str,
               int(p.missing_max_points), float(p.coverage_tau_factor))
        with _LOCK:
            kept = cache.get(_SAMPLED)
        if kept is None or kept[0] != key:
            sub, index, tau = sampled_points(cloud, p)
            found: list[float] = []

            def kept_tau(checkpoint: Checkpoint) -> float:
                if not found:
                    found.append(tau(checkpoint))
                return found[0]

            kept = (key, (sub, index, kept_tau), cloud)  # the array kept holds that memory
            with _LOCK:
                cache[_SAMPLED] = kept
        return kept[1]

    return get


def _neighbours(cache: dict[str, Any]) -> Callable[[cKDTree, np.ndarray, int, float], tuple[np.ndarray, np.ndarray]]:
    """The regions' search of the kept tree, ``tree.query(tree.data[rows], k, distance_upper_bound=link)``,
    each row's answer kept in ``cache`` for that tree, k and link (a row's answer depends on them
    alone; the unexplained points of one update are mostly those of the next): only rows not asked
    before are searched. Returned as the kept table itself (distances, int32 cloud rows; a row of the
    tree each), ``rows`` filled, read in place (the regions' compiled pass, missing_parts._from_kept;
    a gather of a pruned arm's 30k rows took 5 ms). 12 bytes a point of the tree per neighbour, made
    at the first update."""

    def get(tree: cKDTree, rows: np.ndarray, k: int, link: float) -> tuple[np.ndarray, np.ndarray]:
        with _LOCK:
            kept = cache.get(_NEIGHBOURS)
            if kept is None or kept[0] is not tree or kept[1] != (k, link):
                kept = (tree, (k, link), np.zeros(tree.n, bool), np.empty((tree.n, k)), np.empty((tree.n, k), np.int32))
                cache[_NEIGHBOURS] = kept
            _, _, known, d, j = kept
            new = rows[~known[rows]]
        if len(new):
            dn, jn = tree.query(tree.data[new], k=k, distance_upper_bound=link, workers=query_workers(len(new)))
            with _LOCK:
                d[new], j[new] = dn.reshape(len(new), k), jn.reshape(len(new), k)
                known[new] = True
        return d, j

    return get


def _coverage_of(ctx: EvalContext, parent: EvalContext | None, cache: dict[str, Any],
                 inside: Callable[[np.ndarray], np.ndarray] | None,
                 checkpoint: Checkpoint) -> Callable[[np.ndarray, np.ndarray, float, CloudIndex], Coverage]:
    """``missing_parts``' coverage of its points for ``ctx``'s curve, by difference from ``parent``'s
    (its memo made here once when the parent has none: the edits of one curve all start from it);
    ``ctx``'s memo kept for the next edit. A memo holds for the same points' index and tau alone."""

    def of(pts: np.ndarray, elements: np.ndarray, tau: float, index: CloudIndex) -> Coverage:
        view = SimpleNamespace(params=ctx.params, cloud_n=pts, cloud_index=index)
        kept = _memo(cache, parent, _MEMOS)
        old = kept[2] if kept is not None and kept[0] is index and kept[1] == tau else None
        if old is None and parent is not None and parent.curve_n is not None:
            spacing = tau / float(ctx.params.coverage_tau_factor)  # as missing_parts spaces them
            before = coverage_elements(parent.curve_n, pts, spacing, ctx.params, inside)[0]
            old = coverage_from(view, None, unique_rows(np.asarray(before, dtype=float))[0], tau)[1]
            if old is not None:
                _store(cache, parent, (index, tau, old), _MEMOS)
        checkpoint(0.2)
        cov, memo = coverage_from(view, old, unique_rows(np.asarray(elements, dtype=float))[0], tau)
        if memo is not None:
            _store(cache, ctx, (index, tau, memo), _MEMOS)
        checkpoint(0.7)
        return cov

    return of


def curve_missing_parts(ctx: EvalContext, cache: dict[str, Any], checkpoint: Checkpoint = no_checkpoint,
                        parent: EvalContext | None = None) -> MissingParts:
    """The curve missing parts stage's result for ``ctx`` (an edit's update of ``parent``'s curve, when
    known), the cloud's tree and the curves' coverage memos kept."""
    cov = ctx.results.get("curve coverage")
    inside, tree = ctx.solid_test(), _cloud_tree(cache)
    return missing_parts(ctx.cloud_n, ctx.curve_n, ctx.params, cov=cov, tau=None if cov is None else cov.tau,
                         what="curve skeleton", to_user=ctx.norm.invert, inside=inside,
                         cloud_tree=tree, nearest_sample=_nearest_sample(cache, tree),
                         neighbours=_neighbours(cache), sampled=_sampled(cache), chords=ctx.chords, checkpoint=checkpoint,
                         coverage_of=_coverage_of(ctx, parent, cache, inside, checkpoint))
