"""Batched actions (docs/repair.md "Batches"): the round's candidates of one kind that only remove
curve (spurious spurs pruned, spurious cycles cut at their weakest edge) and lie apart from one
another, applied together and judged by one update. A batch is kept only when the never-worse rule
accepts it as a whole and, in that same update, every member is seen to do what it would do alone:
its own defect gone, no tallied defect that was not there before, no more components, missing cycles
or missing parts, and each member's own share of curve boundedness, centeredness and outside length
within the rule's bounds. A refused batch names the members to blame (a new defect or lost coverage
nearest to them, their defect still there); the batch is tried again without them, a bounded number
of times, else halved."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from ..curve import CurveSkeleton
from ..diagnostics.branches import decompose_branches
from ..edit import apply
from ..edit.change import keep_vertices
from ..errors import SkelInputError
from ..params import Params
from .findings import Findings
from .guard import verdict
from .proposals import Action

__all__ = ["BATCHED", "Member", "members", "batch_curve", "signatures", "judge", "blame_lost", "log_entries",
           "predicted_worse"]

#: the defect kinds whose actions are batched, in the order they take their turns
BATCHED = ("spurious_branches", "spurious_cycles")
#: the tallied counts a batch may not raise (no member's defect; a rise cannot be laid at one door)
COUNTED = ("components", "missing_cycles", "missing_parts")


@dataclass
class Member:
    """One action of a batch: its ``action``, the edge ids of the current curve it removes, the
    vertex ids it touches (the branch's path or the cycle's vertices) and its defect's ``signature``
    (:func:`signatures`)."""

    action: Action
    edges: np.ndarray
    touched: np.ndarray
    signature: tuple
    key: frozenset = frozenset()


def _key(curve: CurveSkeleton, vertices: np.ndarray) -> frozenset:
    return frozenset(curve.vertices[int(v)].tobytes() for v in vertices)


def signatures(curve: CurveSkeleton, f: Findings) -> dict[tuple, np.ndarray]:
    """Every tallied spur and outside branch of ``f`` by the positions of its vertices (the same
    defect keeps its signature when other parts of the curve go and ids close up), each with its
    vertex ids in ``curve``. Spurious cycles are counted instead (:func:`judge`): the cycle basis
    may describe the cycles left by other edges once one is cut."""
    if f.defects is None:
        return {}
    br = f.defects.branches
    out: dict[tuple, np.ndarray] = {}
    for b in f.defects.spurs.spurious:
        out[("spurious_branches", _key(curve, br.paths[int(b)]))] = np.asarray(br.paths[int(b)], np.int64)
    for b in f.defects.outside.defective_branches():
        out[("outside", _key(curve, br.paths[int(b)]))] = np.asarray(br.paths[int(b)], np.int64)
    return out


def _neighbours(curve: CurveSkeleton, vertices: np.ndarray) -> np.ndarray:
    """``vertices`` and every vertex one edge away."""
    e = curve.edges
    on = np.isin(e, vertices).any(axis=1)
    return np.union1d(vertices, e[on].ravel())


def members(curve: CurveSkeleton, f: Findings, candidates: list[Action], code: str, gap: float,
            skip: set | frozenset = frozenset()) -> list[Member]:
    """The candidates of kind ``code`` that may go together, in their order: a spur's prune, or a
    spurious cycle's cut at its weakest edge (its first cut; the branch deletions are left to the
    single tries), each kept when its vertices and their neighbours share no vertex with a member
    chosen before and lie farther than ``gap`` from them; ``skip``: the keys of members blamed in an
    earlier batch (the positions of a spur's vertices, of a cut edge's ends), left to the single tries."""
    br = f.defects.branches
    pool: list[Member] = []
    seen_cycles: set[int] = set()
    for a in candidates:
        if a.code != code or len(a.entries) != 1:
            continue
        op = a.entries[0]["op"]
        if code == "spurious_branches" and op == "prune_branch":
            touched = np.asarray(br.paths[int(a.target["branch"])], np.int64)
            sig = ("spurious_branches", _key(curve, touched))
            key = sig[1]
        elif code == "spurious_cycles" and op == "cut_cycle" and int(a.target["cycle"]) not in seen_cycles:
            seen_cycles.add(int(a.target["cycle"]))
            cyc = br.cycle_edges(int(a.target["cycle"]))
            touched = np.unique(curve.edges[cyc])
            sig = ("spurious_cycles", int(a.target["cycle"]))
            key = _key(curve, np.asarray(a.entries[0]["args"]["edge"]))
        else:
            continue
        if key in skip:
            continue
        pool.append(Member(a, np.asarray(a.edges, np.int64), touched, sig, key))
    if len(pool) < 2:
        return pool
    owner = np.concatenate([np.full(len(m.touched), i) for i, m in enumerate(pool)])
    tree = cKDTree(curve.vertices[np.concatenate([m.touched for m in pool])]) if gap > 0 else None
    used = np.zeros(curve.n_vertices, bool)
    chosen = np.zeros(len(pool), bool)
    picked = []
    for i, m in enumerate(pool):
        zone = _neighbours(curve, m.touched)
        if used[zone].any():
            continue
        if tree is not None:
            near = tree.query_ball_point(curve.vertices[m.touched], gap)
            if any(chosen[owner[j]].any() for j in near if len(j)):
                continue
        used[zone] = True
        chosen[i] = True
        picked.append(m)
    return picked


def batch_curve(curve: CurveSkeleton, batch: list[Member]) -> CurveSkeleton:
    """``curve`` without the members' edges and the vertices left on no edge of theirs' (a junction
    they end at stays): what the members' operations give one after the other (:func:`log_entries`
    checks it)."""
    gone = np.zeros(curve.n_edges, bool)
    for m in batch:
        gone[m.edges] = True
    rest = curve.edges[~gone]
    keep = np.ones(curve.n_vertices, bool)
    used = np.zeros(curve.n_vertices, bool)
    used[rest.ravel()] = True
    for m in batch:
        if m.action.code == "spurious_branches":
            keep[m.touched[~used[m.touched]]] = False
    return keep_vertices(curve, keep, rest)[0]


def predicted_worse(f: Findings, curve: CurveSkeleton, m: Member, p: Params) -> bool:
    """Whether the member alone would break the rule's bound on curve boundedness, centeredness (the
    shares of samples above beta* and c*, as the Evaluation counts them) or the outside share, from the
    samples and outside lengths of the curve before without the member's edges (the samples of the
    other edges keep their values in an update)."""
    b = f.measures
    on = np.isin(f.sample_edge, m.edges)
    if on.all():
        return True
    for name, vals, star in (("boundedness", f.sample_beta, p.beta_star), ("centeredness", f.sample_c, p.c_star)):
        if b[name] is None:
            continue
        v = vals[~on]
        if name == "centeredness":
            v = v[np.isfinite(v)]  # the share of the valid values, as the Evaluation's summary counts
        if not len(v) or np.count_nonzero(v > star) / len(v) < b[name] - p.repair_score_drop:
            return True
    if b["outside_share"] is not None and f.defects is not None:
        out = np.asarray(f.defects.outside.edge_outside_length, float)
        length = curve.edge_lengths()
        keep = np.ones(len(length), bool)
        keep[m.edges] = False
        if len(out) == len(length) and length[keep].sum() > 0 \
                and float(out[keep].sum() / length[keep].sum()) > b["outside_share"] + p.repair_outside_rise + 1e-12:
            return True
    return False


def _member_points(curve: CurveSkeleton, batch: list[Member]) -> tuple[np.ndarray, np.ndarray]:
    """The members' touched vertices' positions and the member each belongs to."""
    pts = np.vstack([curve.vertices[m.touched] for m in batch])
    owner = np.concatenate([np.full(len(m.touched), i) for i, m in enumerate(batch)])
    return pts, owner


def _nearest_member(curve: CurveSkeleton, batch: list[Member], points: np.ndarray) -> np.ndarray:
    """The index of the member nearest to each point (by its touched vertices)."""
    pts, owner = _member_points(curve, batch)
    return owner[cKDTree(pts).query(np.asarray(points, float).reshape(-1, 3))[1]]


def blame_lost(curve: CurveSkeleton, batch: list[Member], cloud: np.ndarray, before: np.ndarray | None,
               after: np.ndarray | None, gap: float = 0.0) -> set[int]:
    """The members that may have explained the cloud points the batch left unexplained (``before`` /
    ``after``: the missing parts' verdict per cloud point, what completeness is the share of): for each lost point, every member within
    ``gap`` beyond the nearest one (a medial ball reaches past its own edge's vertices); none when the
    verdicts are not comparable."""
    if before is None or after is None or len(before) != len(after) or len(before) != len(cloud):
        return set()
    lost = np.flatnonzero(np.asarray(before, bool) & ~np.asarray(after, bool))
    if not len(lost):
        return set()
    pts, owner = _member_points(curve, batch)
    tree = cKDTree(pts)
    d, _ = tree.query(cloud[lost])
    out: set[int] = set()
    for near in tree.query_ball_point(cloud[lost], d + gap):
        out.update(int(i) for i in owner[near])
    return out


def judge(before: Findings, after: Findings, curve: CurveSkeleton, new_curve: CurveSkeleton, batch: list[Member],
          p: Params) -> tuple[str | None, set[int]]:
    """(why the batch is refused or None, the members to blame): the never-worse rule on the whole
    (:func:`.guard.verdict`), then each member's own part: its defect gone, no new spur or outside
    branch (by the positions of its vertices, :func:`signatures`), no more components, missing cycles
    or missing parts, and spurious cycles fewer by one per cut (a cut lowers the cycle rank by one;
    with no tunnel's cycle lost, each cut alone takes one spurious cycle) or, for prunes, not more."""
    why = verdict(before, after, p)
    sig_b, sig_a = signatures(curve, before), signatures(new_curve, after)
    blamed = {i for i, m in enumerate(batch) if m.signature in sig_a}
    new = [k for k in sig_a if k not in sig_b]
    if new:
        pts = np.vstack([new_curve.vertices[sig_a[k]] for k in new])
        blamed |= {int(i) for i in np.unique(_nearest_member(curve, batch, pts))}
    risen = [k for k in COUNTED if after.tally.get(k, 0) > before.tally.get(k, 0)]
    cuts = sum(m.action.code == "spurious_cycles" for m in batch)
    b_cyc, a_cyc = before.tally.get("spurious_cycles", 0), after.tally.get("spurious_cycles", 0)
    if a_cyc > b_cyc - cuts:
        risen.append("spurious_cycles")
    parts = []
    if blamed:
        parts.append(f"{len(blamed)} of {len(batch)} members leave their defect or make a new one "
                     f"({len(new)} new)")
    if risen:
        parts.append("too many " + ", ".join(f"{k} ({before.tally.get(k, 0)} -> {after.tally.get(k, 0)})" for k in risen))
    if why is None and parts:
        why = "batch: " + "; ".join(parts)
    elif why is not None and parts:
        why += "; batch: " + "; ".join(parts)
    return why, blamed


def log_entries(curve: CurveSkeleton, batch: list[Member]) -> tuple[CurveSkeleton, list[list[dict[str, Any]]]]:
    """The members' operations one after the other, each in the ids of the curve the ones before it
    left (a prune names the branch ending at its free end; a cut, its edge's ends), and the curve they
    give; raises SkelInputError when a member no longer applies."""
    cur = curve
    ids = np.arange(curve.n_vertices, dtype=np.int64)  # old vertex id -> id in cur (-1: gone)
    out: list[list[dict[str, Any]]] = []
    for m in batch:
        if m.action.code == "spurious_cycles":
            a, b = (int(ids[v]) for v in m.action.entries[0]["args"]["edge"])
            entry = {"op": "cut_cycle", "args": {"edge": [min(a, b), max(a, b)]}}
        else:
            path = ids[m.touched]
            deg = cur.degrees()
            ends = [int(v) for v in (path[0], path[-1]) if v >= 0 and deg[v] == 1]
            if not ends or (path < 0).any():
                raise SkelInputError("a spur of the batch has no free end left")
            br = decompose_branches(cur)
            inc = np.flatnonzero((cur.edges == ends[0]).any(axis=1))
            k = int(br.edge_branch[inc[0]])
            if set(int(v) for v in br.paths[k]) != set(int(v) for v in path):
                raise SkelInputError("a spur of the batch is no longer one branch")
            entry = {"op": "prune_branch", "args": {"branch": k}}
        cur, change = apply(cur, entry, f"{m.action.code} batch member")
        ids = np.where(ids >= 0, np.asarray(change.id_map)[np.maximum(ids, 0)], -1)
        out.append([entry])
    return cur, out
