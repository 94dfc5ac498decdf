"""unique_rows keeps its answer for the same large array (docs/performance.md 6.4): the same values,
read-only, recomputed when the array's contents change, and an evaluation that reads it from every
stage gives the arrays it gives without the memo."""

from __future__ import annotations

import numpy as np
import pytest

from skelcore import Params, evaluate, geometry, shapes


def _points(n: int) -> np.ndarray:
    rng = np.random.default_rng(0)
    return np.repeat(rng.normal(size=(n // 2, 3)), 2, axis=0)  # every row twice


def test_the_memo_gives_the_same_answer_read_only_and_follows_changes(monkeypatch):
    pts = _points(2 * geometry._MEMO_ROWS)
    first = geometry.unique_rows(pts)
    again = geometry.unique_rows(pts)
    assert all(a is b for a, b in zip(first, again))  # kept
    fresh = geometry._unique_rows(pts, geometry.no_checkpoint)
    assert all(np.array_equal(a, b) for a, b in zip(first, fresh))
    assert len(first[0]) == len(pts) // 2 and not first[0].flags.writeable
    with pytest.raises(ValueError):
        first[1][0] = 5
    pts[0] = [9.0, 9.0, 9.0]  # the same object, other contents: computed again
    changed = geometry.unique_rows(pts)
    assert len(changed[0]) == len(pts) // 2 + 1 and changed[0] is not first[0]
    copy = pts.copy()  # another object with the same contents: its own entry, the same values
    assert np.array_equal(geometry.unique_rows(copy)[0], changed[0])


def test_an_evaluation_with_the_memo_equals_one_without(monkeypatch):
    """A 70k-point torus (above the memo's size): every stage that asks reads the kept answer; no stage
    writes into it (read-only arrays would raise), and every array is the one computed afresh."""
    n = 70_000
    shape = shapes.torus(n, seed=1)
    skeletal = shape.skeletal + np.random.default_rng(1).normal(scale=0.01, size=shape.skeletal.shape)
    curve = (shape.curve_vertices, shape.curve_edges)
    params = Params(coverage_max_points=n + 1)
    with_memo = evaluate(shape.cloud, skeletal, curve, params)
    monkeypatch.setattr(geometry, "_MEMO_ROWS", 10**12)
    without = evaluate(shape.cloud, skeletal, curve, params)
    for a, b in ((with_memo.skeletal.boundedness, without.skeletal.boundedness),
                 (with_memo.skeletal.smoothness, without.skeletal.smoothness),
                 (with_memo.skeletal.centeredness_raw, without.skeletal.centeredness_raw),
                 (with_memo.coverage_skeletal.gap, without.coverage_skeletal.gap),
                 (with_memo.topology.skeletal_barcode, without.topology.skeletal_barcode)):
        assert np.array_equal(a, b, equal_nan=True)
    assert with_memo.summary() == without.summary()
