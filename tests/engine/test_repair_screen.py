"""The repair's first look at a candidate (docs/repair.md "Never worse"): the update without
diagnostics, then coverage and completeness alone, gives the measures of the whole update and refuses
only what the never-worse rule refuses; and every defect kind has its turn before a round gives up. Checked on
a crop of a traced neuron of resources/neurons (its real twigs: pruning them loses completeness)."""

from __future__ import annotations

import numpy as np
import pytest

import skelcore
from skelcore import Params
from diagnostics_helpers import traced_crop
from skelcore.benchmark.neurons import load_neuron
from skelcore.curve import CurveSkeleton
from skelcore.edit import apply
from skelcore.skeleton_repair.findings import read_findings
from skelcore.skeleton_repair.guard import verdict
from skelcore.skeleton_repair.proposals import Action, _prunes
from skelcore.skeleton_repair.run import in_turn
from skelcore.skeleton_repair.screen import explained, first_look

NEURON, CENTRE_NODE, CROP = "1734350788", 1990, 300.0  # a tuning neuron; a ball around one junction


@pytest.fixture(scope="module")
def crop() -> tuple[np.ndarray, CurveSkeleton]:
    """The cloud of 30k samples of the whole mesh and the traced skeleton, both cut to the ball."""
    cloud, v, e, _, _ = traced_crop(load_neuron(NEURON), CENTRE_NODE, CROP, 30_000)
    return cloud, CurveSkeleton.from_raw(v, e)


def test_the_first_look_agrees_with_the_whole_update(crop):
    """Every terminal branch of the crop pruned in turn: the first look's completeness, boundedness
    and centeredness are the whole update's, and what it refuses the rule refuses."""
    cloud, curve = crop
    p = Params()
    ev = skelcore.evaluate(cloud, curve=curve)
    found = read_findings(ev)
    terminal = [b for b, kind in enumerate(found.defects.branches.kind) if kind == "terminal"]
    assert len(terminal) >= 3
    refused = 0
    for act in _prunes(found, np.asarray(terminal[:3]), "spurious_branches", "test"):
        new = apply(curve, act.entries[0], "test")[0]
        pre = ev.update(new, diagnostics=False)
        seen, why = first_look(found, pre, p)
        full, done = read_findings(ev.update(new)), read_findings(pre.complete_update())
        assert done.measures == full.measures and done.tally == full.tally  # the coverage handed on
        for m in ("completeness", "boundedness", "centeredness"):
            assert seen[m] == pytest.approx(full.measures[m], abs=1e-12)
        if why is not None:
            refused += 1
            assert why.startswith("worse: ") and verdict(found, full, p) is not None
    assert refused >= 1  # real twigs explain cloud of their own


def _act(code: str, k: int) -> Action:
    return Action(code, {"k": k}, "", [])


def test_every_defect_kind_has_its_turn():
    """Eight cuts of spurious cycles before two fills of a missing part and an outside edge: the six
    tries of a round are the first six cuts as before, then both fills (a region refused leaves the
    next its try) and the first of the other kinds left out."""
    acts = [_act("spurious_cycles", k) for k in range(8)] + [_act("incomplete", 0), _act("incomplete", 1),
                                                             _act("outside", 0), _act("outside", 1)]
    order = [(a.code, a.target["k"]) for a in in_turn(acts, 6)]
    assert order == [("spurious_cycles", k) for k in range(6)] + [("incomplete", 0), ("incomplete", 1),
                                                                  ("outside", 0)]
    assert in_turn(acts[:3], 6) == acts[:3]


def test_a_fill_is_made_only_when_a_round_asks_for_it(monkeypatch):
    """A tube whose curve stops halfway: its upper half is a counted missing region. The fills come one
    at a time in fill_missing's order, and the first (the region's axis curve) is made without the
    region's skeletonization, which a round whose tries are taken never asks for."""
    from skelcore import shapes
    from skelcore.skeleton_repair import fill

    s = shapes.cylinder(1500)
    half = s.curve_edges[(s.curve_edges < 11).all(axis=1)]
    curve = CurveSkeleton.from_raw(s.curve_vertices[:11], half)
    found = read_findings(skelcore.evaluate(s.cloud, curve=curve))
    assert found.missing.counted
    every = fill.fill_missing(curve, found.missing, s.cloud)
    assert len(every) >= 2 and [a.entries for a in fill.fill_actions(curve, found.missing, s.cloud)] == \
        [a.entries for a in every]

    def no(*_a, **_k):
        raise AssertionError("made before it was asked for")

    monkeypatch.setattr(fill, "_skeleton_entries", no)
    first = next(fill.fill_actions(curve, found.missing, s.cloud))
    assert first.entries == every[0].entries and "axis curve" in first.reason


def test_a_first_look_reads_the_completeness_alone(crop):
    """Terminal branches of the crop pruned in turn: the first look's completeness is the whole
    missing parts' to the bit; a refused action leaves its missing parts' regions unfound when the
    coverage holds (else, an element in the air, they were found to know it), one that passes has them
    found before its whole update, which reads them."""
    from skelcore.diagnostics.missing_parts import coverage_holds

    cloud, curve = crop
    p = Params()
    ev = skelcore.evaluate(cloud, curve=curve)
    found = read_findings(ev)
    terminal = [b for b, kind in enumerate(found.defects.branches.kind) if kind == "terminal"]
    refused = 0
    for act in _prunes(found, np.asarray(terminal[:4]), "spurious_branches", "test"):
        new = apply(curve, act.entries[0], "test")[0]
        pre = ev.update(new, diagnostics=False)
        seen, why = first_look(found, pre, p)
        whole = ev.update(new).source.ctx.results["curve missing parts"]
        assert seen["completeness"] == whole.completeness
        ctx = pre.source.ctx
        held = coverage_holds(ctx.cloud_n, ctx.curve_n, ctx.results["curve coverage"], p, ctx.solid_test())
        assert ("curve missing parts" in pre.diagnostics_left_out) == (why is not None and held)
        assert np.array_equal(explained(pre), whole.explained)  # what a refused batch blames its members by
        refused += why is not None
    assert refused >= 1


def test_the_repair_is_the_same_with_the_completeness_alone(monkeypatch):
    """A tube whose curve stops halfway (a fill kept, one refused at first look): the same log, curve
    and last Evaluation whether the first looks find the missing parts' regions or not."""
    from skelcore import shapes
    from skelcore.skeleton_repair import fill, repair, screen

    s = shapes.cylinder(1500)
    half = s.curve_edges[(s.curve_edges < 11).all(axis=1)]
    curve = CurveSkeleton.from_raw(s.curve_vertices[:11], half)
    monkeypatch.setattr(fill, "SLABS_FIRST", False)  # the tube's end seen all round: a fill refused all the same
    assert screen.COMPLETENESS_ALONE is True
    alone = []
    made = screen.completeness_alone
    monkeypatch.setattr(screen, "completeness_alone", lambda *a: alone.append(made(*a)) or alone[-1])
    fast = repair(s.cloud, curve)
    assert alone and None not in alone  # the tube's coverage holds: every first look read it alone
    monkeypatch.setattr(screen, "COMPLETENESS_ALONE", False)
    slow = repair(s.cloud, curve)
    assert fast.accepted >= 1 and any(r["why"]["defects_after"] is None for r in fast.log["rejected"])
    assert fast.log == slow.log and fast.stopped == slow.stopped
    assert all(np.array_equal(getattr(fast.curve, f), getattr(slow.curve, f)) for f in ("vertices", "edges"))
    assert fast.after.summary() == slow.after.summary()
    assert [w.message for w in fast.after.warnings] == [w.message for w in slow.after.warnings]


def test_a_refused_first_look_knows_what_its_coverage_explains():
    """A tube whose curve stops halfway, shortened by two more edges: refused at first look for its
    completeness, its missing parts' regions not found, and the verdict per cloud point it gives a
    refused batch to blame its members by is the whole update's."""
    from skelcore import shapes

    s = shapes.cylinder(1500)
    half = s.curve_edges[(s.curve_edges < 11).all(axis=1)]
    curve = CurveSkeleton.from_raw(s.curve_vertices[:11], half)
    ev = skelcore.evaluate(s.cloud, curve=curve)
    found = read_findings(ev)
    shorter = CurveSkeleton.from_raw(s.curve_vertices[:9], half[(half < 9).all(axis=1)])
    pre = ev.update(shorter, diagnostics=False)
    seen, why = first_look(found, pre, Params())
    assert why is not None and why.startswith("worse: completeness")
    assert "curve missing parts" in pre.diagnostics_left_out
    whole = ev.update(shorter).source.ctx.results["curve missing parts"]
    assert seen["completeness"] == whole.completeness and np.array_equal(explained(pre), whole.explained)
    assert np.array_equal(explained(ev), ev.source.ctx.results["curve missing parts"].explained)
