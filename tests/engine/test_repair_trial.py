"""The repair's tries made cheaper without changing them (docs/repair.md "The repair's cost"): an
action's run of added vertices and edges applied in one rebuild gives the curve the edit gives entry
by entry (its bits, its refusals), and a round's fills made only when their try is reached give the
same log and curve as making every fill first. Checked on a tube whose curve covers only its middle
(two counted missing regions, one at each end)."""

from __future__ import annotations

import numpy as np
import pytest

from skelcore import shapes
from skelcore.curve import CurveSkeleton
from skelcore.errors import SkelInputError
from skelcore.skeleton_repair import fill, repair, run
from skelcore.skeleton_repair.trial import tried, tried_one_by_one


def _same_bits(a: CurveSkeleton, b: CurveSkeleton) -> bool:
    return all(getattr(a, f) is None and getattr(b, f) is None
               or getattr(a, f).dtype == getattr(b, f).dtype and getattr(a, f).tobytes() == getattr(b, f).tobytes()
               for f in ("vertices", "edges", "vertex_map", "radius"))


@pytest.fixture(scope="module")
def middle() -> tuple[np.ndarray, CurveSkeleton]:
    s = shapes.cylinder(1500, length=6.0, seed=3)
    lo, hi = 6, 15  # of 21 vertices
    keep = s.curve_edges[((s.curve_edges >= lo) & (s.curve_edges < hi)).all(axis=1)] - lo
    return s.cloud, CurveSkeleton.from_raw(s.curve_vertices[lo:hi], keep)


def _entries(curve: CurveSkeleton, rng: np.random.Generator) -> list[dict]:
    """A reroute-like action: an edge deleted, a new path from one of its ends, a closing edge."""
    a, b = (int(x) for x in curve.edges[len(curve.edges) // 2])
    n = curve.n_vertices
    out = [{"op": "delete_edge", "args": {"edge": [a, b]}}]
    out += [{"op": "add_vertex", "args": {"position": [float(x) for x in rng.normal(size=3)],
                                         "attach_to": a if i == 0 else n + i - 1}} for i in range(12)]
    out += [{"op": "add_vertex", "args": {"position": [0.1, 0.2, 0.3], "attach_to": None}}]
    return out + [{"op": "add_edge", "args": {"edge": [n + 11, n + 12]}}, {"op": "add_edge", "args": {"edge": [b, n + 12]}}]


def test_a_run_of_adds_is_the_edits_curve_to_the_bit(middle):
    _, curve = middle
    rng = np.random.default_rng(0)
    with_radius = CurveSkeleton(curve.vertices, curve.edges, curve.vertex_map, np.linspace(0.1, 0.2, curve.n_vertices))
    for c in (curve, with_radius):
        entries = _entries(c, rng)
        assert _same_bits(tried(c, entries, "x"), tried_one_by_one(c, entries, "x"))
        n = c.n_vertices
        for bad in ({"edge": [n + 3, n + 4]}, {"edge": [int(c.edges[0, 0]), int(c.edges[0, 1])]}, {"edge": [2, 2]},
                    {"edge": [0, n + 40]}, {"edge": [0, n + 5], "t": 0.5}):
            wrong = entries[:-1] + [{"op": "add_edge", "args": bad}] + entries[-1:]
            with pytest.raises(SkelInputError) as fast:
                tried(c, wrong, "x")
            with pytest.raises(SkelInputError) as slow:
                tried_one_by_one(c, wrong, "x")
            assert str(fast.value) == str(slow.value) and f"step {len(entries) - 1}" in str(fast.value)


def test_a_run_of_adds_takes_every_form_of_position_as_the_edit_does(middle):
    """Positions as a fill writes them (lists of three Python floats, taken as they are), and as numpy
    arrays, tuples or integers (numpy's conversion): the edit's curve to the bit; a non-finite one is
    refused with the edit's message."""
    _, curve = middle
    entries = _entries(curve, np.random.default_rng(1))
    for k, form in ((1, np.array([0.5, 0.25, 1.0])), (2, (1.0, 2.0, 3.0)), (3, [1, 2, 3]), (4, [np.float64(0.5), 1.0, 2.0])):
        entries[k] = {"op": "add_vertex", "args": {**entries[k]["args"], "position": form}}
    assert _same_bits(tried(curve, entries, "x"), tried_one_by_one(curve, entries, "x"))
    for bad in ([0.0, float("nan"), 1.0], [0.0, float("inf"), 1.0], [0.0, 1.0]):
        wrong = [dict(e) for e in entries]
        wrong[5] = {"op": "add_vertex", "args": {**entries[5]["args"], "position": bad}}
        with pytest.raises(SkelInputError) as fast:
            tried(curve, wrong, "x")
        with pytest.raises(SkelInputError) as slow:
            tried_one_by_one(curve, wrong, "x")
        assert str(fast.value) == str(slow.value)


def test_fills_made_when_reached_give_the_same_repair(middle, monkeypatch):
    """The same log (kept and refused, with their measures) and the same curve to the bit as making
    every fill a round may try first and applying every entry alone. A candidate that fails (a vertex
    moved out of the shape) heads every round and a round tries three, so that fills wait beyond the
    round's first tries, made only when reached, and the refused one goes last after a kept fill."""
    from skelcore import Params
    from skelcore.skeleton_repair.proposals import Action

    cloud, curve = middle
    propose, after = run.propose, fill.Fills.after

    def with_refused(cur, *args, **kwargs):
        out = {"op": "move_vertex", "args": {"vertex": 1, "position": [float(x) for x in cur.vertices[1] + [1.0, 0, 0]]}}
        return [Action("outside", {"vertex": 1}, "moved out", [out])] + propose(cur, *args, **kwargs)

    reached: list[int] = []

    def counted(self, k):
        for a in after(self, k):
            reached.append(k)
            yield a

    monkeypatch.setattr(run, "propose", with_refused)
    monkeypatch.setattr(fill.Fills, "after", counted)
    monkeypatch.setattr(fill, "SLABS_FIRST", False)  # the tube's end is seen all round: two rounds all the same
    p = Params(repair_max_tries=3)
    assert fill.WHEN_REACHED is True
    fast = repair(cloud, curve, params=p)
    assert reached  # fills made when reached
    monkeypatch.setattr(fill, "WHEN_REACHED", False)
    monkeypatch.setattr(run, "tried", tried_one_by_one)
    slow = repair(cloud, curve, params=p)
    assert sum(o["why"]["defect"] == "incomplete" for o in fast.log["operations"]) >= 1
    assert sum(r["why"]["defect"] == "outside" for r in fast.log["rejected"]) >= 2
    assert fast.log == slow.log and _same_bits(fast.curve, slow.curve)
    assert fast.after.summary() == slow.after.summary()


def test_a_fill_is_made_when_its_try_is_reached():
    """The first ``k`` fills are made at once, the others one by one as they are reached, never
    beyond the cap, in the generator's order."""
    made: list[int] = []

    def gen():
        for i in range(5):
            made.append(i)
            yield i

    fills = fill.Fills(gen(), 4)
    assert fills.first(2) == [0, 1] and made == [0, 1]
    rest = fills.after(2)
    assert next(rest) == 2 and made == [0, 1, 2]
    assert list(rest) == [3] and made == [0, 1, 2, 3]  # the cap: the fifth is never made
    few = fill.Fills(iter([7]), 4)
    assert few.first(3) == [7] and list(few.after(1)) == [] and few.first(-1) == []


def test_the_lazy_order_is_in_turns_order():
    """tries_in_turn over the known candidates and the fills still to make gives in_turn's order of
    the whole list, with and without actions tried last."""
    from skelcore.skeleton_repair.proposals import Action

    acts = [Action("spurious_cycles", {"k": k}, "", []) for k in range(7)] + \
        [Action("incomplete", {"k": k}, "", []) for k in range(4)]
    for late in (None, lambda a: a.target["k"] in (1, 2)):
        whole = run.in_turn(acts, 6, late)
        assert list(run.tries_in_turn(acts[:8], 6, late, iter(acts[8:]))) == whole
