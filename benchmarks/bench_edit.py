"""Proofreading: :meth:`Evaluation.update` after one edit against a fresh ``evaluate`` of the edited curve,
on a Y of 100k points (curve only) and, with ``--bench-large``, of 1M points: a branch pruned, an edge
deleted, a vertex moved. ``update`` alone (the four metrics, diagnostics=False: the viewer's first phase),
``complete_update`` of that (the curve's coverage and diagnostics: its second phase), ``update`` with the
diagnostics in one call, and the fresh evaluation. Each case's extra_info holds the p95 of its rounds (the
targets: 100 ms at 100k, 500 ms at 1M, docs/performance.md "Updating after an edit"), its median CPU
seconds, the samples scored again and, with the diagnostics, how many of the cloud points the spur test
tests it asked again (the others keep the base evaluation's answers, diagnostics/spur_cache.py). The base evaluation is made once per size, untimed."""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import pytest

import skelcore.edit as E
from skelcore import evaluate, shapes

EDITS = ["prune_branch", "delete_edge", "move_vertex"]
HOW = ["update", "second_phase", "update_with_diagnostics", "fresh"]


@lru_cache(maxsize=1)
def _base(n: int):
    sh = shapes.y_shape(n, seed=0)
    return sh.cloud, evaluate(sh.cloud, curve=(sh.curve_vertices, sh.curve_edges))


def _edit(name: str, curve):
    if name == "prune_branch":
        return E.prune_branch(curve, 0)
    if name == "delete_edge":
        return E.delete_edge(curve, tuple(curve.edges[5]))
    return E.move_vertex(curve, 5, curve.vertices[5] + np.array([0.0, 0.01, 0.0]))


def _run(measure, benchmark, n: int, edit: str, how: str, rounds: int, fresh_rounds: int) -> None:
    cloud, ev = _base(n)
    new, change = _edit(edit, ev.curve.curve)
    if how == "fresh":
        out = measure(lambda: evaluate(cloud, curve=new), rounds=fresh_rounds)
    elif how == "second_phase":
        quick = ev.update(change, diagnostics=False)
        out = measure(quick.complete_update, rounds=rounds)
    else:
        out = measure(lambda: ev.update(change, diagnostics=how != "update"), rounds=rounds)
    old = {p.tobytes() for p in ev.curve.samples}
    rescored = sum(p.tobytes() not in old for p in out.curve.samples)
    benchmark.extra_info["n_points"] = n
    benchmark.extra_info["samples"] = len(out.curve.samples)
    benchmark.extra_info["samples_at_new_places"] = int(rescored)
    memo = getattr(out.source.ctx, "spur_memo", None) if out.source is not None else None
    if how in ("second_phase", "update_with_diagnostics") and memo is not None:
        asked, of = memo.asked  # the spur test's points asked again, of those it tests
        benchmark.extra_info["spur_points_asked"] = [asked, of]


@pytest.mark.parametrize("how", HOW)
@pytest.mark.parametrize("edit", EDITS)
def test_edit_y_100k(measure, benchmark, edit, how):
    _run(measure, benchmark, 100_000, edit, how, rounds=20, fresh_rounds=3)


@pytest.mark.large
@pytest.mark.parametrize("how", HOW)
@pytest.mark.parametrize("edit", EDITS)
def test_edit_y_1m(measure, benchmark, edit, how):
    _run(measure, benchmark, 1_000_000, edit, how, rounds=10, fresh_rounds=1)
