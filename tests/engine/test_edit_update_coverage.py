"""The curve's coverage after an edit, updated by difference (skelcore/edit/coverage_update.py): the same
gaps and verdicts as computing it whole, on a noisy Y (the noise shortfall grows the radii) and a clean
torus, after edits that remove, add and move balls, and along a chain of edits; the difference path is
the one taken (its memo kept per curve)."""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import pytest

import skelcore.edit as E
from skelcore import Params, evaluate, shapes
from skelcore.edit import coverage_update as CU
from skelcore.metrics.coverage import coverage


@lru_cache(maxsize=None)
def _base(name: str):
    params = Params(coverage_exact_points=1000) if name == "torus, estimated" else Params()
    if name.startswith("torus"):  # estimated: coverage on a subsample of 1000 points, spread to all
        sh = shapes.torus(3000, n_curve=24, seed=2)
        cloud = sh.cloud
    else:  # Gaussian noise of a fifth of the radius: the radii grow by the noise shortfall
        sh = shapes.y_shape(3000, seed=4, n_curve_per_arm=8)
        cloud = sh.cloud + np.random.default_rng(5).normal(0.0, 0.05, sh.cloud.shape)
    return cloud, evaluate(cloud, curve=(sh.curve_vertices, sh.curve_edges), params=params)


def _whole(ev):
    """The coverage computed whole from the edited curve's context."""
    ctx = ev.source.ctx
    elements, tau = CU._elements(ctx)
    return coverage(ctx.cloud_n, elements, ctx.params, tau, index=ctx.cloud_index)



@pytest.mark.parametrize("name", ["noisy y", "torus", "torus, estimated"])
def test_coverage_by_difference_equals_coverage_computed_whole(name, monkeypatch):
    _, ev = _base(name)
    whole = []
    monkeypatch.setattr(CU, "_full", lambda *a, f=CU._full: (whole.append(1), f(*a))[1])
    curve = ev.curve.curve
    changes = [E.delete_edge(curve, tuple(curve.edges[3]))[1],
               E.move_vertex(curve, 4, curve.vertices[4] + np.array([0.0, 0.03, 0.01]))[1]]
    for change in changes:
        up = ev.update(change)
        ref = _whole(up)
        np.testing.assert_array_equal(up.coverage_curve.gap, ref.gap)
        np.testing.assert_array_equal(up.coverage_curve.covered, ref.covered)
        assert up.coverage_curve.fraction == ref.fraction and up.coverage_curve.max_gap == ref.max_gap
        assert up.coverage_curve.subsample == ref.subsample == (1000 if "estimated" in name else None)
    if name == "noisy y":
        memo = CU._memo(ev.source.cache, ev.source.ctx)
        assert (memo.r > memo.r0).all()  # the shortfall path was the one taken
    # the base's memo, once: each update then went by difference (with noise, the shortfall's ratio
    # moves with the curve: the radii change, all is asked again, the kept elements' distances reused)
    assert len(whole) == (3 if name == "noisy y" else 1)
    # a chain: the second edit from the first's update, in two phases
    first = ev.update(changes[0])
    c2 = E.move_vertex(first.curve.curve, 2, first.curve.curve.vertices[2] + np.array([0.02, 0.0, 0.0]))[1]
    second = first.update(c2, diagnostics=False).complete_update()
    ref = _whole(second)
    np.testing.assert_array_equal(second.coverage_curve.gap, ref.gap)
    np.testing.assert_array_equal(second.coverage_curve.covered, ref.covered)


def test_the_noise_samples_nearest_element_by_difference_is_the_shortfalls_own():
    """Each noise-sample point's nearest element kept by difference equals the shortfall's own search
    (the same distances and rows), ties included: elements on a grid, so many points lie as near two."""
    from skelcore.metrics import coverage as C

    _, ev = _base("torus")
    curve = ev.curve.curve
    new = ev.update(E.delete_edge(curve, tuple(curve.edges[3]))[1])
    for up in (new, new.update(E.move_vertex(new.curve.curve, 6, new.curve.curve.vertices[6] + 0.02)[1])):
        memo = CU._memo(up.source.cache, up.source.ctx)
        d, i = C._nearest_element(memo.elements, C._noise_sample(up.source.ctx.cloud_n)[0])
        np.testing.assert_array_equal(memo.near[0], d)
        np.testing.assert_array_equal(memo.near[1], i)


def test_a_first_look_completed_hands_its_coverage_on_to_the_next_edits(monkeypatch):
    """A repair's candidate kept (its coverage computed at its first look, then its defects by
    ``complete_update``) is the base of the next round: that Evaluation's next edits go by difference
    from the coverage of the first look, none computed whole, the same values."""
    from skelcore.edit.incremental import compute_left_out

    _, ev = _base("torus")
    curve = ev.curve.curve
    pre = ev.update(E.delete_edge(curve, tuple(curve.edges[3]))[1], diagnostics=False)
    compute_left_out(pre, ("curve coverage", "curve missing parts"))
    kept = pre.complete_update()
    whole = []
    monkeypatch.setattr(CU, "_full", lambda *a, f=CU._full: (whole.append(1), f(*a))[1])
    nxt = kept.curve.curve
    up = kept.update(E.move_vertex(nxt, 4, nxt.vertices[4] + np.array([0.0, 0.03, 0.01]))[1])
    ref = _whole(up)
    np.testing.assert_array_equal(up.coverage_curve.gap, ref.gap)
    np.testing.assert_array_equal(up.coverage_curve.covered, ref.covered)
    assert whole == []


@pytest.mark.parametrize("share", [0.0, 2.0])
def test_the_points_near_removed_balls_asked_again_unprobed_give_the_same_coverage(share, monkeypatch):
    """The points near removed balls all asked again of every ball (the probe finds most decided by a
    removed one: ``REDO_SHARE`` 0) or only those a removed ball decided (never skipped: 2): the same
    gaps and verdicts as computing the coverage whole, after a pruned branch and a deleted edge."""
    sh = shapes.y_shape(4000, seed=3, n_curve_per_arm=8)
    ev = evaluate(sh.cloud, curve=(sh.curve_vertices, sh.curve_edges))
    monkeypatch.setattr(CU, "REDO_SHARE", share)
    answers, asked = [], []  # the points near removed balls; how many the removed balls' tree asked

    def sub_tree(*a, f=CU._sub_tree):
        tree = f(*a)
        tree.balls = lambda q, *b, g=tree.balls, **k: (asked.append(len(q)), g(q, *b, **k))[1]
        return tree

    monkeypatch.setattr(CU, "_sub_tree", sub_tree)
    monkeypatch.setattr(CU, "_decided_by_removed",
                        lambda *a, f=CU._decided_by_removed: (answers.append(len(a[0])), f(*a))[1])
    curve = ev.curve.curve
    for change in (E.prune_branch(curve, 0)[1], E.delete_edge(curve, tuple(curve.edges[3]))[1]):
        up = ev.update(change)
        ref = _whole(up)
        np.testing.assert_array_equal(up.coverage_curve.gap, ref.gap)
        np.testing.assert_array_equal(up.coverage_curve.covered, ref.covered)
    assert len(answers) == 2 and min(answers) > 4 * CU.REDO_PROBE
    probes = [-(-n // CU.REDO_PROBE) for n in answers]  # the path asked for was taken
    assert asked == (probes if share == 0.0 else [probes[0], answers[0], probes[1], answers[1]])
