"""Batched actions (docs/repair.md "Batches"): the spurs of a tube pruned in one round, the log
replayed to the same curve as one action per round gives, each member of a kept batch accepted by
the never-worse rule alone, and a batch refused when it would hide a member that alone is refused."""

from __future__ import annotations

import json

import numpy as np
import pytest

import skelcore
from skelcore import CurveSkeleton, Params, shapes
from skelcore.edit import apply, replay
from skelcore.skeleton_repair.batch import Member, batch_curve, judge, members, predicted_worse
from skelcore.skeleton_repair.findings import read_findings
from skelcore.skeleton_repair.guard import verdict
from skelcore.skeleton_repair.proposals import propose
from skelcore.stages import evaluate

#: the tube's path vertices the twigs leave from (far apart: 1.2 along a tube of radius 0.5)
ROOTS = (4, 10, 16)


@pytest.fixture(scope="module")
def tube() -> shapes.Shape:
    return shapes.cylinder(3000)


def _twigs(s: shapes.Shape, roots: tuple[int, ...] = ROOTS) -> CurveSkeleton:
    """The tube's path with a two-edge twig inside the wall from each root, sideways in turn."""
    v, e = s.curve_vertices, s.curve_edges
    verts, edges = [v], [e]
    n = len(v)
    for k, i in enumerate(roots):
        d = np.array([[1.0, 0, 0], [0, 1.0, 0], [-1.0, 0, 0]])[k % 3]
        z = np.array([0, 0, v[i, 2]])
        verts.append(np.array([z + 0.18 * d + [0, 0, 0.05], z + 0.33 * d + [0, 0, 0.1]]))
        edges.append(np.array([[i, n], [n, n + 1]]))
        n += 2
    return CurveSkeleton.from_raw(np.vstack(verts), np.vstack(edges))


@pytest.fixture(scope="module")
def batched(tube):
    return skelcore.repair(tube.cloud, _twigs(tube))


def _batches(log: dict) -> list[list[dict]]:
    """The kept operations grouped by batch (each member's one operation), in log order."""
    out: list[list[dict]] = []
    for op in log["operations"]:
        tag = op["why"].get("batch")
        if tag is None:
            continue
        if tag.startswith("1 of"):
            out.append([])
        out[-1].append(op)
    return out


def test_the_twigs_are_pruned_together_in_one_round(batched):
    r = batched
    assert r.tally_before["spurious_branches"] == len(ROOTS)
    assert r.tally_after["spurious_branches"] == 0
    groups = _batches(r.log)
    assert groups and len(groups[0]) == len(ROOTS)
    assert [o["op"] for o in groups[0]] == ["prune_branch"] * len(ROOTS)
    assert all(o["why"]["defect"] == "spurious_branches" for o in groups[0])
    assert r.accepted >= len(ROOTS)


def test_the_log_replays_and_one_per_round_gives_the_same_curve(tube, batched):
    start = _twigs(tube)
    again, _ = replay(start, json.loads(json.dumps(batched.log)))
    assert again.vertices.tobytes() == batched.curve.vertices.tobytes()
    assert again.edges.tobytes() == batched.curve.edges.tobytes()
    single = skelcore.repair(tube.cloud, start, params=Params(repair_batch_tries=0))
    assert not _batches(single.log)
    assert single.curve.vertices.tobytes() == batched.curve.vertices.tobytes()
    assert single.curve.edges.tobytes() == batched.curve.edges.tobytes()


def test_every_member_of_a_kept_batch_is_kept_alone(tube, batched):
    """The batch hides no refusal: each member's operation, applied alone to the curve the batch
    started from, is accepted by the never-worse rule (a fresh evaluation)."""
    p = Params()
    cur = _twigs(tube)
    done = 0
    for op in batched.log["operations"]:
        tag = op["why"].get("batch")
        if tag is not None and tag.startswith("1 of"):
            base, members_left = cur, int(tag.split(" of ")[1])
            found = read_findings(evaluate(tube.cloud, curve=base, params=p))
            ids = np.arange(base.n_vertices)
        if tag is not None:  # the member's operation in the ids of the batch's start curve
            entry = {"op": op["op"], "args": dict(op["args"])}
            if op["op"] == "prune_branch":
                cur_br = skelcore.diagnostics.branches.decompose_branches(cur)
                path = cur_br.paths[op["args"]["branch"]]
                back = {int(n): int(o) for o, n in enumerate(ids) if n >= 0}
                old = {back[int(v)] for v in path}
                base_br = skelcore.diagnostics.branches.decompose_branches(base)
                entry["args"]["branch"] = next(k for k, pth in enumerate(base_br.paths) if set(map(int, pth)) == old)
            alone, _ = apply(base, entry)
            assert verdict(found, read_findings(evaluate(tube.cloud, curve=alone, params=p)), p) is None
            done += 1
        cur, change = apply(cur, {"op": op["op"], "args": op["args"]})
        if tag is not None:
            ids = np.where(ids >= 0, np.asarray(change.id_map)[np.maximum(ids, 0)], -1)
            members_left -= 1
    assert done >= len(ROOTS)


def test_a_batch_that_would_hide_a_refused_member_is_refused(tube):
    """Two members, one of which removes nothing (alone: no progress, refused): the batch as a whole
    lowers the count of defects, so the ordinary rule would keep it; the batch rule blames that member."""
    p = Params()
    cur = _twigs(tube, ROOTS[:2])
    ev = evaluate(tube.cloud, curve=cur, params=p)
    found = read_findings(ev)
    pool = members(cur, found, propose(cur, found), "spurious_branches", 0.4)
    assert len(pool) == 2
    idle = Member(pool[1].action, np.zeros(0, np.int64), pool[1].touched, pool[1].signature)
    batch = [pool[0], idle]
    new = batch_curve(cur, batch)
    after = read_findings(ev.update(new))
    assert verdict(found, after, p) is None  # the whole: one spur fewer
    why, blamed = judge(found, after, cur, new, batch, p)
    assert why is not None and blamed == {1}
    why, blamed = judge(found, after, cur, new, batch[:1], p)
    assert why is None and not blamed


def test_a_member_that_alone_would_lower_centeredness_is_left_out(tube):
    p = Params()
    cur = _twigs(tube, ROOTS[:2])
    found = read_findings(evaluate(tube.cloud, curve=cur, params=p))
    pool = members(cur, found, propose(cur, found), "spurious_branches", 0.4)
    assert not any(predicted_worse(found, cur, m, p) for m in pool)
    central = np.flatnonzero(found.sample_c >= np.nanmedian(found.sample_c))
    heavy = Member(pool[0].action, np.unique(found.sample_edge[central]), pool[0].touched, pool[0].signature)
    assert predicted_worse(found, cur, heavy, p)
