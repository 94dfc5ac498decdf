"""The repair loop (docs/repair.md): evaluate, try the candidate actions in order, keep the first the
never-worse rule accepts, evaluate again (:meth:`skelcore.Evaluation.update`), until no tallied defect
is left, no candidate helps or ``Params.repair_max_rounds`` is reached. Every action tried is logged
with why: kept ones in the edit log's ``operations`` (replayable with ``skelcore edit``), rejected
ones under ``rejected``."""

from __future__ import annotations

import time
from itertools import chain
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any, Callable, Iterable, Iterator

import numpy as np

from ..curve import CurveSkeleton
from ..edit import new_log
from ..errors import Cancelled, SkelInputError
from ..evaluation import Evaluation
from ..params import Params
from ..stages import evaluate
from .checks import check_curve, check_frame
from .findings import read_findings
from .from_skeletal import HOW, curve_from_skeletal
from .guard import FILL, verdict
from .proposals import Action, propose
from .batch_round import BatchState, batch_step
from .fill import Fills, fill_actions
from .phases import PhaseClock
from .recentre import RECENTRE, recentre, settled, vertex_centeredness
from .reroute import route_inside
from .screen import first_look, first_update, whole_update, with_scan_checks
from .skeletal_out import repaired_skeletal
from .trial import tried

__all__ = ["RepairResult", "repair", "in_turn", "tries_in_turn"]

#: defect warnings no action answers yet (docs/repair.md "What is left")
UNTALLIED = {"incomplete"}


@dataclass
class RepairResult:
    """``curve``: the repaired curve; ``log``: the edit log from the input curve (each operation with a
    ``why``; ``rejected`` lists the actions refused); ``before`` / ``after``: the first and last
    Evaluation; ``accepted`` / ``rejected``: counts; ``stopped``: why the loop ended; ``seconds``;
    ``extracted``: how the curve was made when only a skeletal set was given; ``skeletal``: the
    repaired skeletal set (:func:`.skeletal_out.repaired_skeletal`); ``phases``: CPU seconds and runs
    per phase (:class:`.phases.PhaseClock`)."""

    curve: CurveSkeleton
    log: dict[str, Any]
    before: Evaluation
    after: Evaluation
    accepted: int = 0
    rejected: int = 0
    stopped: str = ""
    seconds: float = 0.0
    tally_before: dict[str, int] = field(default_factory=dict)
    tally_after: dict[str, int] = field(default_factory=dict)
    extracted: str = ""
    phases: dict[str, dict[str, float | int]] = field(default_factory=dict)

    @property
    def start(self) -> CurveSkeleton:
        """The curve the repair started from (given, or extracted from the skeletal set)."""
        return CurveSkeleton.coerce(self.before.source.args["curve"], "curve")

    @cached_property
    def skeletal(self) -> np.ndarray:
        """The repaired skeletal set, one row per cloud row (docs/repair.md)."""
        args = self.before.source.args
        return repaired_skeletal(args["cloud"], self.start, self.curve, args.get("skeletal"))[0]


def _rounded(measures: dict[str, float | None]) -> dict[str, float | None]:
    return {k: None if v is None else round(v, 4) for k, v in measures.items()}


def _in_shape(ev: Evaluation) -> tuple[Callable[[np.ndarray], np.ndarray] | None, float, Any]:
    """Inside the shape (the diagnostics' voxelized interior, holes filled), its voxel in user units,
    and the router through it (:func:`.reroute.route_inside`)."""
    ctx = getattr(ev.source, "ctx", None)
    if ctx is None:
        return None, 0.0, None
    vs = ctx.interior()
    solid = vs.solid()

    def inside(points: np.ndarray) -> np.ndarray:
        ijk = vs.index_of(ctx.norm.apply(np.asarray(points, float)))
        return solid[ijk[:, 0], ijk[:, 1], ijk[:, 2]]

    def route(curve: CurveSkeleton, edge: int) -> np.ndarray | None:
        return route_inside(curve, edge, vs, ctx.norm)

    return inside, float(vs.size) / float(ctx.norm.scale), route


def _no_defect_left(found: Any) -> str:
    left = sorted(set(found.warnings) & UNTALLIED)
    return f"left: {', '.join(left)} (not acted on)" if left else "no defect left"


def _drift(cur: CurveSkeleton, ev: Evaluation, found: Any, p: Params, memo: dict,
           rejected: list[dict[str, Any]], want: int) -> list[Action]:
    """The first ``want`` re-centrings of ``cur`` (none when ``repair_recentre`` is off), cut only at
    the vertices the evaluation's own samples do not find centred, branch by branch in the order of
    their samples' centeredness (:func:`.recentre.recentre`); one once rejected is not tried again
    (the same moves)."""
    if not p.repair_recentre or want < 1:
        return []
    skip = settled(cur, found.sample_edge, found.sample_t, found.sample_c, p.c_star)
    vc = vertex_centeredness(cur, found.sample_edge, found.sample_t, found.sample_c)
    return recentre(cur, np.asarray(ev.source.args["cloud"], float), p, memo, skip, vc, want,
                    lambda a: all(a.entries != r["entries"] for r in rejected))


def in_turn(actions: list[Action], tries: int, late: Callable[[Action], bool] | None = None) -> list[Action]:
    """The first ``tries`` candidates, then the first of each defect kind left out of them, and every
    fill left out (the round makes at most ``tries``): tried only when all those failed (the loop
    stops at the first kept), so the fills of missing parts waiting behind six refused cycle cuts
    still have their turn (one region refused leaves the next its try). ``late``: the actions refused
    since the last kept action that was not a fill, tried last (a fill only adds curve, so what was
    refused before it mostly stays refused, and the next fill comes first); none is left out."""
    return list(tries_in_turn(actions, tries, late))


def tries_in_turn(actions: list[Action], tries: int, late: Callable[[Action], bool] | None = None,
                  more: Iterable[Action] = ()) -> Iterator[Action]:
    """:func:`in_turn`'s order of ``actions`` followed by ``more`` (fills, beyond the first ``tries``
    candidates), one at a time: a fill of ``more`` is made only when it is reached (:class:`.fill.Fills`)."""
    head = actions[:tries]
    kinds = {a.code for a in head}
    rest = []
    for a in actions[tries:]:
        if a.code == FILL:
            rest.append(a)
        elif a.code not in kinds:
            kinds.add(a.code)
            rest.append(a)
    if late is None:
        yield from head + rest
        yield from more
        return
    last = []  # stable: the late ones last, in their order
    for a in chain(head + rest, more):
        if late(a):
            last.append(a)
        else:
            yield a
    yield from last


def _same(curve: CurveSkeleton, action: Action) -> tuple:
    """What makes two candidates the same action across rounds whose kept actions only added curve
    (fills: every vertex and edge stays, ids may move): its kind, its operations and the vertex pairs
    of the edges it touches (a fill: the places of its new vertices; else its entries)."""
    ops = tuple(e["op"] for e in action.entries)
    if len(action.edges):
        return action.code, ops, tuple(sorted(map(tuple, curve.edges[action.edges].tolist())))
    if action.code == FILL:  # the new vertices' places (a kept fill moves the ids they will take)
        return action.code, ops, tuple(tuple(e["args"]["position"]) for e in action.entries if e["op"] == "add_vertex")
    return action.code, ops, repr(action.entries)


def repair(cloud: np.ndarray, curve: CurveSkeleton | tuple | None = None, skeletal: np.ndarray | None = None,
           params: Params | None = None, cancel: Callable[[], bool] | None = None,
           progress: Callable[[float, str], None] | None = None) -> RepairResult:
    """Repair ``curve`` against ``cloud`` from the judge's findings (docs/repair.md); deterministic for
    a given input. Refuses (SkelInputError, one line) a curve without edges, one of more than
    ``params.repair_max_components`` components and one the ``frame`` check finds in another frame;
    ``cancel()`` returning True raises :class:`~skelcore.Cancelled` at the next evaluation or action.
    ``curve`` None: the curve extracted from ``skeletal`` (:mod:`.from_skeletal`) is repaired."""
    t0 = time.perf_counter()
    p = params or Params()
    extracted = ""
    if curve is None and skeletal is not None:
        curve, extracted = curve_from_skeletal(cloud, skeletal), f"the curve was extracted from the skeletal set by {HOW}"
    if curve is None:
        raise SkelInputError("repair needs a curve skeleton or a skeletal set")
    start = CurveSkeleton.coerce(curve, "curve")
    check_curve(start, p)

    def check() -> None:
        if cancel is not None and cancel():
            raise Cancelled("repair cancelled")

    def tell(fraction: float, what: str) -> None:
        if progress is not None:
            progress(min(1.0, fraction), what)

    tell(0.0, "evaluating the curve")
    clock = PhaseClock()
    with clock.phase("first evaluation"):
        first = evaluate(cloud, skeletal=skeletal, curve=start, params=p, cancel=cancel)
    check_frame(first)
    ev, cur, found = first, start, read_findings(first)
    scanned = True  # whether ev ran the real-scan trust checks (screen.whole_update)
    ops: list[dict[str, Any]] = []
    rejected: list[dict[str, Any]] = []
    tally0 = dict(found.tally)
    stopped = f"repair_max_rounds={p.repair_max_rounds} reached"
    memo: dict = {}  # cross-sections cut by the re-centring, kept over the rounds
    parts: dict = {}  # the missing regions' curves made for fills, kept over the rounds
    behind: set[tuple] = set()  # refused since the last kept action that was not a fill: tried last
    batches = BatchState()
    for rnd in range(p.repair_max_rounds):
        check()
        drift = None
        if found.total == 0:
            with clock.phase("re-centring cuts"):
                drift = _drift(cur, ev, found, p, memo, rejected, p.repair_max_tries)
        if found.total == 0 and not drift:
            stopped = _no_defect_left(found)
            break
        tell(rnd / p.repair_max_rounds, f"round {rnd + 1}")
        with clock.phase("proposals"):
            inside, voxel, route = _in_shape(ev)
            candidates = propose(cur, found, inside, p.repair_join_step * voxel, route)
            fills = Fills(fill_actions(cur, found.missing, np.asarray(ev.source.args["cloud"], float),
                                       p.repair_max_tries, parts, p.repair_all_round, p.repair_fill_points)
                          if p.repair_fill_missing else iter(()),
                          p.repair_max_tries, lambda: clock.phase("proposals"))
        ahead = fills.first(p.repair_max_tries - len(candidates))  # those the head and the count need
        candidates += ahead
        if len(candidates) < p.repair_max_tries:  # re-centrings come last: cut only when they may be tried
            if drift is None:
                with clock.phase("re-centring cuts"):
                    drift = _drift(cur, ev, found, p, memo, rejected, p.repair_max_tries - len(candidates))
            candidates += drift
        kept = batch_step(ev, cur, found, candidates, p, batches, clock, rejected, cancel)
        if kept is not None:  # a batch of one kind's actions apart from one another (batch_round.py)
            ev, cur, found, batch_ops, scanned = kept
            ops += batch_ops
            behind = set()
            continue
        done, refused_now = False, []
        late = (lambda a: _same(cur, a) in behind) if behind else None
        for action in tries_in_turn(candidates, p.repair_max_tries, late, fills.after(len(ahead))):
            check()
            why: dict[str, Any] = {"defect": action.code, **action.target, "reason": action.reason,
                                   "local_before": found.local(action.edges), "before": _rounded(found.measures),
                                   "defects_before": found.total}
            try:
                new = tried(cur, action.entries, action.code)
            except SkelInputError as exc:
                rejected.append({"entries": action.entries, "why": {**why, "rejected": f"not applicable: {exc}"}})
                refused_now.append(_same(cur, action))
                continue
            kept = new.edges.max(axis=1) < cur.n_vertices if action.code == FILL else None
            with clock.phase("first look"):  # the cheap first look (screen.py), then the rest
                pre = first_update(ev, new)
                seen, refusal = first_look(found, pre, p, recentring=action.code == RECENTRE, kept=kept)
            if "fill_centeredness" in seen:
                why["fill_centeredness"] = _rounded({"c": seen.pop("fill_centeredness")})["c"]
            if refusal is not None:
                why.update(after=_rounded(seen), defects_after=None)
                rejected.append({"entries": action.entries, "why": {**why, "rejected": refusal}})
                refused_now.append(_same(cur, action))
                continue
            with clock.phase("whole update"):
                new_ev, new_scanned = whole_update(pre, cancel)
                new_found = read_findings(new_ev)
            why.update(after=_rounded(new_found.measures), defects_after=new_found.total)
            refusal = verdict(found, new_found, p, recentring=action.code == RECENTRE, outside=action.code == "outside",
                              kept=kept)
            if refusal is not None:
                rejected.append({"entries": action.entries, "why": {**why, "rejected": refusal}})
                refused_now.append(_same(cur, action))
                continue
            for k, entry in enumerate(action.entries):
                ops.append({**entry, "why": {**why, "step": f"{k + 1} of {len(action.entries)}"}})
            ev, cur, found, done, scanned = new_ev, new, new_found, True, new_scanned
            behind = behind.union(refused_now) if action.code == FILL else set()
            break
        if not done and batches.rest_until:  # before giving up, the kinds resting from batches
            kept = batch_step(ev, cur, found, candidates, p, batches, clock, rejected, cancel, last=True)
            if kept is not None:
                ev, cur, found, batch_ops, scanned = kept
                ops += batch_ops
                behind = set()
                continue
        if not done:
            stopped = ("no candidate action helps" if candidates else "no action for the defects left"
                       ) if found.total else _no_defect_left(found)
            break
    if not scanned:  # the last Evaluation's real-scan warnings, which its update left out
        with clock.phase("scan checks"):
            ev = with_scan_checks(ev, cur)
    log = new_log(start, [])
    log["operations"] = ops
    log["rejected"] = rejected
    log["repair"] = {"stopped": stopped, "defects_before": tally0, "defects_after": dict(found.tally),
                     "measures_before": _rounded(read_findings(first).measures),
                     "measures_after": _rounded(found.measures)}
    if extracted:
        log["repair"]["extracted"] = extracted
    tell(1.0, "done")
    n_acc = sum(1 for o in ops if o["why"]["step"].startswith("1 of"))
    return RepairResult(curve=cur, log=log, before=first, after=ev, accepted=n_acc, rejected=len(rejected),
                        stopped=stopped, seconds=time.perf_counter() - t0, tally_before=tally0,
                        tally_after=dict(found.tally), extracted=extracted, phases=clock.table())
