"""The never-worse rule (docs/repair.md "Never worse"): an action is kept only when it lowers the count
of defects and costs no completeness, no outside share and no noticeable curve boundedness or
centeredness; a re-centring must instead raise curve centeredness by ``Params.repair_centre_gain``
with no more defects and no lower boundedness, and an action on a branch outside the shape may instead
lower the outside length share by ``Params.repair_outside_gain`` with as many defects, no tunnel lost
and no piece cut off (the tally counts a branch with two edges outside once, until both are back);
otherwise it is rejected, with the reason logged."""

from __future__ import annotations

from ..params import Params
from .findings import Findings

__all__ = ["verdict", "worse", "recentred", "KEPT_WHOLE"]

#: the defects an outside action that lowers the outside share may not add: a tunnel's cycle lost (a
#: chord through a torus's hole deleted) or a piece cut off; a spur for a spurious cycle is a fair trade
KEPT_WHOLE = ("missing_cycles", "components")


def verdict(before: Findings, after: Findings, params: Params, recentring: bool = False,
            outside: bool = False) -> str | None:
    """None when ``after`` may replace ``before``; else why not (one phrase). ``recentring``: the
    action only moved vertices to their cross-sections' centres; ``outside``: it answered an
    ``outside`` defect (docs/repair.md "Never worse")."""
    b, a = before.measures, after.measures
    why = worse(b, a, params)
    if why:
        return "worse: " + "; ".join(why)
    if recentring:  # a gain of its own whatever the count: what the first look decides (screen.py)
        why = recentred(b, a, params)
        if why is None and after.total > before.total:
            why = f"no progress: {before.total} defect(s) before, {after.total} after"
        return why
    if outside and after.total == before.total and all(after.tally[k] <= before.tally[k] for k in KEPT_WHOLE):
        return _less_outside(b, a, params, before.total)
    if after.total >= before.total:
        return f"no progress: {before.total} defect(s) before, {after.total} after"
    return None


def worse(b: dict, a: dict, params: Params, *, completeness: bool = True) -> list[str]:
    """The never-worse bounds the measures ``a`` break against ``b`` (one phrase each): completeness
    (unless ``completeness`` is False: not known yet), the outside share (when both are known), curve
    boundedness and centeredness."""
    why = []
    if completeness and b["completeness"] is not None and (
            a["completeness"] is None or a["completeness"] < b["completeness"] - params.repair_completeness_drop):
        why.append(f"completeness {b['completeness']:.4f} -> {_r(a['completeness'])}")
    if b["outside_share"] is not None and a["outside_share"] is not None \
            and a["outside_share"] > b["outside_share"] + params.repair_outside_rise:
        why.append(f"outside share {b['outside_share']:.4f} -> {a['outside_share']:.4f}")
    for m in ("boundedness", "centeredness"):
        if b[m] is not None and (a[m] is None or a[m] < b[m] - params.repair_score_drop):
            why.append(f"curve {m} {b[m]:.4f} -> {_r(a[m])}")
    return why


def recentred(b: dict, a: dict, params: Params) -> str | None:
    """None when a re-centring raises curve centeredness by the gain and does not lower curve
    boundedness at all (``b`` / ``a``: the measures before / after); else why not."""
    if b["boundedness"] is not None and (a["boundedness"] or 0.0) < b["boundedness"]:
        return f"worse: curve boundedness {b['boundedness']:.4f} -> {_r(a['boundedness'])}"
    if b["centeredness"] is None or a["centeredness"] is None \
            or a["centeredness"] < b["centeredness"] + params.repair_centre_gain:
        return (f"no progress: curve centeredness {_r(b['centeredness'])} -> {_r(a['centeredness'])} "
                f"(less than repair_centre_gain={params.repair_centre_gain} higher)")
    return None


def _less_outside(b: dict, a: dict, params: Params, total: int) -> str | None:
    """An action on an outside branch with as many defects, none of :data:`KEPT_WHOLE` more: kept when
    the outside length share falls by ``repair_outside_gain`` (one of a branch's outside edges
    rerouted, the branch still counted)."""
    if b["outside_share"] is None or a["outside_share"] is None \
            or a["outside_share"] > b["outside_share"] - params.repair_outside_gain:
        return (f"no progress: {total} defect(s) before and after, outside share {_r(b['outside_share'])} -> "
                f"{_r(a['outside_share'])} (less than repair_outside_gain={params.repair_outside_gain} lower)")
    return None


def _r(x: float | None) -> float | None:
    return None if x is None else round(x, 4)
