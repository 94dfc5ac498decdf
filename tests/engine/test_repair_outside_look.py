"""A fill's outside test at its first look (docs/repair.md "The repair's cost"): the same outside
tally and share as the whole update's, and a fill that adds an outside branch refused without its
whole update, the repair keeping and refusing the same actions and giving the same curve as the
slower path, its log differing only in such refusals (``defects_after`` null, the outside branches
named). Checked on a tube whose curve covers only its middle, a fill poking out of the wall."""

from __future__ import annotations

import numpy as np
import pytest

from skelcore import Params, evaluate, shapes
from skelcore.curve import CurveSkeleton
from skelcore.skeleton_repair import fill, repair, run, screen
from skelcore.skeleton_repair.findings import read_findings
from skelcore.skeleton_repair.guard import verdict
from skelcore.skeleton_repair.outside_look import outside_of
from skelcore.skeleton_repair.proposals import Action

#: bounds wide enough that a fill poking out of the wall passes the measures and meets the outside test
LOOSE = Params(repair_score_drop=0.3, repair_outside_rise=0.5)


@pytest.fixture(scope="module")
def middle() -> tuple[np.ndarray, CurveSkeleton, np.ndarray]:
    s = shapes.cylinder(1500, length=6.0, seed=3)
    lo, hi = 6, 15  # of 21 vertices along z
    keep = s.curve_edges[((s.curve_edges >= lo) & (s.curve_edges < hi)).all(axis=1)] - lo
    return s.cloud, CurveSkeleton.from_raw(s.curve_vertices[lo:hi], keep), s.curve_vertices[:lo][::-1]


def _poking(curve: CurveSkeleton, axis: np.ndarray, poke: float) -> list[dict]:
    """A fill down the missing end's axis from vertex 0, with a side vertex ``poke`` beyond the wall
    (radius 0.5) when ``poke`` > 0."""
    n = curve.n_vertices
    out = [{"op": "add_vertex", "args": {"position": [float(x) for x in p], "attach_to": 0 if i == 0 else n + i - 1}}
           for i, p in enumerate(axis)]
    if poke > 0:
        out.append({"op": "add_vertex", "args": {"position": [float(axis[2, 0]) + 0.5 + poke, float(axis[2, 1]),
                                                              float(axis[2, 2])], "attach_to": n + 2}})
    return out


def test_the_first_looks_outside_test_is_the_whole_updates(middle):
    cloud, curve, axis = middle
    ev = evaluate(cloud, curve=curve)
    seen = []
    for poke in (0.0, 0.6, 1.0):
        new = run.tried(curve, _poking(curve, axis, poke), "incomplete")
        pre = screen.first_update(ev, new)
        out = outside_of(pre)
        whole = screen.whole_update(pre)[0].source.ctx.results["curve defects"].outside
        assert out.to_dict() == whole.to_dict()
        assert np.array_equal(out.defective_branches(), whole.defective_branches())
        seen.append(len(out.defective_branches()))
    assert seen[0] == 0 and seen[1] >= 1  # the poke is found outside


def test_a_fill_adding_an_outside_branch_is_refused_at_first_look(middle):
    """Refused at first look, naming the fill's outside branch and its reach, as the whole rule refuses
    it; the same fill without the poke passes the first look."""
    cloud, curve, axis = middle
    ev = evaluate(cloud, curve=curve, params=LOOSE)
    before = read_findings(ev)
    assert before.tally["outside"] == 0
    for poke, refused in ((0.0, False), (0.6, True)):
        new = run.tried(curve, _poking(curve, axis, poke), "incomplete")
        kept = new.edges.max(axis=1) < curve.n_vertices
        pre = screen.first_update(ev, new)
        seen, why = screen.first_look(before, pre, LOOSE, kept=kept)
        if not refused:
            assert why is None
            continue
        assert why.startswith("no progress: more outside (0 -> 1): the fill's outside branch: branch ")
        assert "local radii of length outside, reaching" in why and "local radii out)" in why and seen["outside_share"] > 0
        whole = read_findings(screen.whole_update(pre)[0])
        assert "outside (0 -> 1)" in verdict(before, whole, LOOSE, kept=kept)
        assert whole.measures["outside_share"] == seen["outside_share"]


def test_the_repair_refuses_the_same_fills_with_and_without_the_outside_test(middle, monkeypatch):
    """The same operations, curve to the bit and last Evaluation; the refused fill that pokes out is
    the one log entry that differs: at first look (``defects_after`` null, its outside branch named)
    against after its whole update."""
    cloud, curve, axis = middle
    made = fill.fill_actions

    def poking_first(cur, *args, **kwargs):
        if cur.n_vertices == curve.n_vertices:  # the first round: the poking fill heads the fills
            yield Action("incomplete", {"region": -1}, "a fill poking out of the wall", _poking(cur, axis, 0.6))
        yield from made(cur, *args, **kwargs)

    monkeypatch.setattr(run, "fill_actions", poking_first)
    assert screen.OUTSIDE_FIRST is True
    p = LOOSE.replace(repair_max_rounds=2)
    fast = repair(cloud, curve, params=p)
    monkeypatch.setattr(screen, "OUTSIDE_FIRST", False)
    slow = repair(cloud, curve, params=p)
    assert fast.accepted >= 1 and fast.log["operations"] == slow.log["operations"]
    assert all(np.array_equal(getattr(fast.curve, f), getattr(slow.curve, f)) for f in ("vertices", "edges"))
    assert fast.after.summary() == slow.after.summary() and fast.log["repair"] == slow.log["repair"]
    changed = [(f, s) for f, s in zip(fast.log["rejected"], slow.log["rejected"]) if f != s]
    assert len(fast.log["rejected"]) == len(slow.log["rejected"]) and len(changed) == 1
    f, s = changed[0]
    assert f["entries"] == s["entries"]
    assert f["why"]["defects_after"] is None and s["why"]["defects_after"] is not None
    assert f["why"]["rejected"].startswith("no progress: more outside (0 -> 1): the fill's outside branch")
    assert "outside (0 -> 1)" in s["why"]["rejected"]
