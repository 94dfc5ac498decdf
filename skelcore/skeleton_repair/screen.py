"""A candidate's cheap first look (docs/repair.md "Never worse"): the edited curve's update without its
diagnostics (curve boundedness and centeredness), then its coverage and completeness alone. An action
these already make worse is rejected without the curve's defects, the dear part of an update at 100k
points; one that passes gets the whole update (:meth:`~skelcore.Evaluation.complete_update`). The
measures are those the whole update gives (the same stages on the same inputs, computed once), so the
decisions are the never-worse rule's own."""

from __future__ import annotations

import numpy as np

from ..edit.incremental import LEFT_OUT
from ..evaluation import Evaluation
from ..geometry import no_checkpoint
from ..params import Params
from ..stages.catalogue import CATALOGUE
from .findings import Findings

__all__ = ["first_look"]

_STAGES = {s.name: s for s in CATALOGUE}


def _num(x: object) -> float | None:
    return None if x is None or not np.isfinite(float(x)) else float(x)  # type: ignore[arg-type]


def _completeness(pre: Evaluation) -> tuple[bool, float | None]:
    """(whether it could be computed, the curve's completeness) of an update left without
    diagnostics, as the whole update's stages compute it (the coverage, then the missing parts). Both
    results are handed on to ``pre``'s context as computed, so that its
    :meth:`~skelcore.Evaluation.complete_update` adds only the curve's defects."""
    ctx = getattr(pre.source, "ctx", None)
    cov, miss = _STAGES["curve coverage"], _STAGES["curve missing parts"]
    if ctx is None or not miss.applies(ctx) or ctx.not_computed.get(miss.name) != LEFT_OUT:
        return False, None
    for stage in (cov, miss):
        if stage.applies(ctx):
            ctx.results[stage.name] = stage.fn(ctx, no_checkpoint)
            ctx.not_computed.pop(stage.name, None)
    return True, _num(getattr(ctx.results[miss.name], "completeness", None))


def first_look(before: Findings, pre: Evaluation, params: Params) -> tuple[dict[str, float | None], str | None]:
    """(the measures known without defects, why the action is worse or None) for ``pre``, the
    candidate's ``update(..., diagnostics=False)``: completeness, curve boundedness and centeredness
    against ``before`` with the bounds of :func:`.guard.verdict`; the outside share stays None."""
    s = pre.summary()
    known, completeness = _completeness(pre)
    a = {"completeness": completeness, "outside_share": None,
         "boundedness": _num(s["boundedness"]["curve"]), "centeredness": _num(s["centeredness"]["curve"])}
    b = before.measures
    why = []
    if known and b["completeness"] is not None and (
            a["completeness"] is None or a["completeness"] < b["completeness"] - params.repair_completeness_drop):
        why.append(f"completeness {b['completeness']:.4f} -> {_r(a['completeness'])}")
    for m in ("boundedness", "centeredness"):
        if b[m] is not None and (a[m] is None or a[m] < b[m] - params.repair_score_drop):
            why.append(f"curve {m} {b[m]:.4f} -> {_r(a[m])}")
    return a, ("worse: " + "; ".join(why)) if why else None


def _r(x: float | None) -> float | None:
    return None if x is None else round(x, 4)
