"""Proofreading: :meth:`Evaluation.update` after one edit against a fresh ``evaluate`` of the edited curve,
on a Y of 100k points (curve only): a branch pruned, an edge deleted, a vertex moved. ``update`` alone
(the four metrics, diagnostics=False), with the curve's coverage and diagnostics, and the fresh evaluation;
the samples scored again are in each case's extra_info. The base evaluation is made once, untimed."""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import pytest

import skelcore.edit as E
from skelcore import evaluate, shapes

N = 100_000


@lru_cache(maxsize=1)
def _base():
    sh = shapes.y_shape(N, seed=0)
    return sh.cloud, evaluate(sh.cloud, curve=(sh.curve_vertices, sh.curve_edges))


def _edit(name: str, curve):
    if name == "prune_branch":
        return E.prune_branch(curve, 0)
    if name == "delete_edge":
        return E.delete_edge(curve, tuple(curve.edges[5]))
    return E.move_vertex(curve, 5, curve.vertices[5] + np.array([0.0, 0.01, 0.0]))


@pytest.mark.parametrize("how", ["update", "update_with_diagnostics", "fresh"])
@pytest.mark.parametrize("edit", ["prune_branch", "delete_edge", "move_vertex"])
def test_edit_y_100k(measure, benchmark, edit, how):
    cloud, ev = _base()
    new, change = _edit(edit, ev.curve.curve)
    if how == "fresh":
        out = measure(lambda: evaluate(cloud, curve=new), rounds=3)
    else:
        out = measure(lambda: ev.update(change, diagnostics=how != "update"), rounds=7)
    old = {p.tobytes() for p in ev.curve.samples}
    rescored = sum(p.tobytes() not in old for p in out.curve.samples)
    benchmark.extra_info["n_points"] = N
    benchmark.extra_info["samples"] = len(out.curve.samples)
    benchmark.extra_info["samples_at_new_places"] = int(rescored)
