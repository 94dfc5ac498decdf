"""A round's batches (docs/repair.md "Batches"): before the single tries, each batched kind in its turn
(the kind after the last kept batch's first) gathers its members (:func:`.batch.members`), is judged
by one update and kept, or tried again without the members to blame, at most
``Params.repair_batch_tries`` times; a member once blamed is left to the single tries; a kind whose
batches are all refused in a round rests 2, then 4, 8... rounds (its actions single tries meanwhile),
so a curve whose actions are mostly refused pays a few batch tries now and then."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from ..curve import CurveSkeleton
from ..errors import SkelInputError
from ..evaluation import Evaluation
from ..params import Params
from .batch import BATCHED, Member, batch_curve, blame_lost, judge, log_entries, members, predicted_worse
from .findings import Findings, read_findings
from .phases import PhaseClock
from .proposals import Action
from .screen import explained, first_look, first_update, whole_update

__all__ = ["BatchState", "batch_step"]


@dataclass
class BatchState:
    """Whose turn it is (an index into :data:`.batch.BATCHED`), the round, per kind the round it is
    batched again after its batches were all refused and how many times they were, and the keys of
    the members blamed so far (:attr:`.batch.Member.key`)."""

    turn: int = 0
    round: int = 0
    rest_until: dict[str, int] = field(default_factory=dict)
    refused: dict[str, int] = field(default_factory=dict)
    blamed: set = field(default_factory=set)


def _rounded(measures: dict[str, float | None]) -> dict[str, float | None]:
    return {k: None if v is None else round(v, 4) for k, v in measures.items()}


def _gap(curve: CurveSkeleton, p: Params) -> float:
    if not curve.n_edges:
        return 0.0
    e = curve.edges
    return p.repair_batch_gap * float(np.median(np.linalg.norm(curve.vertices[e[:, 0]] - curve.vertices[e[:, 1]], axis=1)))


def _smaller(batch: list[Member], blamed: set[int]) -> list[Member]:
    """The first half of the batch without the members to blame (a new defect is laid at the nearest
    member's door, not always the right one: halving reaches a sound batch in a few tries)."""
    rest = [m for i, m in enumerate(batch) if i not in blamed]
    return rest[: len(rest) // 2]


def batch_step(ev: Evaluation, cur: CurveSkeleton, found: Findings, candidates: list[Action], p: Params,
               state: BatchState, clock: PhaseClock, rejected: list[dict[str, Any]],
               cancel: Callable[[], bool] | None = None, last: bool = False
               ) -> tuple[Evaluation, CurveSkeleton, Findings, list[dict[str, Any]], bool] | None:
    """The first batch the rule keeps this round: (its evaluation, curve, findings, the log's
    operations with their ``why``, whether its evaluation ran the real-scan checks), or None; refused batches are appended to ``rejected``.
    ``last``: the round's single tries all failed; the resting kinds have their turn before the
    repair stops."""
    if p.repair_batch_tries < 1 or found.defects is None:
        return None
    cloud = np.asarray(ev.source.args["cloud"], float)
    n = len(BATCHED)
    state.round += 0 if last else 1
    for code in (BATCHED[(state.turn + k) % n] for k in range(n)):
        if (state.round < state.rest_until.get(code, 0)) != last:
            continue  # a resting kind waits; on the last call only the resting kinds are tried
        with clock.phase("proposals"):
            batch = members(cur, found, candidates, code, _gap(cur, p), state.blamed)
            batch = [m for m in batch if not predicted_worse(found, cur, m, p)] if len(batch) >= 2 else []
        if len(batch) < 2:
            continue
        for _ in range(p.repair_batch_tries):
            if len(batch) < 2:
                break
            why: dict[str, Any] = {"defect": code, "batch": len(batch),
                                   "targets": [m.action.target for m in batch],
                                   "reason": f"{len(batch)} {code} actions apart from one another, judged as one",
                                   "before": _rounded(found.measures), "defects_before": found.total}
            new = batch_curve(cur, batch)
            with clock.phase("first look"):
                pre = first_update(ev, new)
                seen, refusal = first_look(found, pre, p)
            if refusal is not None:
                why.update(after=_rounded(seen), defects_after=None)
                blamed = blame_lost(cur, batch, cloud, explained(ev), explained(pre), _gap(cur, p))
                rejected.append({"entries": [], "why": {**why, "rejected": refusal, "blamed": len(blamed)}})
                state.blamed |= {batch[i].key for i in blamed}
                batch = _smaller(batch, blamed)
                continue
            with clock.phase("whole update"):
                new_ev, scanned = whole_update(pre, cancel)
                new_found = read_findings(new_ev)
            why.update(after=_rounded(new_found.measures), defects_after=new_found.total)
            refusal, blamed = judge(found, new_found, cur, new, batch, p)
            if refusal is None:
                try:
                    replayed, entries = log_entries(cur, batch)
                except SkelInputError as exc:
                    refusal = f"not applicable: {exc}"
                else:
                    if not (np.array_equal(replayed.vertices, new.vertices) and np.array_equal(replayed.edges, new.edges)):
                        refusal = "not applicable: the members' operations give another curve"
            if refusal is not None:
                rejected.append({"entries": [], "why": {**why, "rejected": refusal, "blamed": len(blamed)}})
                state.blamed |= {batch[i].key for i in blamed}
                batch = _smaller(batch, blamed)
                continue
            ops = []
            shared = {k: why[k] for k in ("before", "defects_before", "after", "defects_after")}
            for i, (m, member_entries) in enumerate(zip(batch, entries)):
                a = m.action
                own = {"defect": a.code, **a.target, "reason": a.reason, "local_before": found.local(m.edges),
                       **shared, "batch": f"{i + 1} of {len(batch)}"}
                for k, entry in enumerate(member_entries):
                    ops.append({**entry, "why": {**own, "step": f"{k + 1} of {len(member_entries)}"}})
            state.turn = (BATCHED.index(code) + 1) % n
            return new_ev, new, new_found, ops, scanned
        state.refused[code] = state.refused.get(code, 0) + 1
        state.rest_until[code] = state.round + 2 ** state.refused[code]
    return None
