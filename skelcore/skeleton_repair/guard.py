"""The never-worse rule (docs/repair.md "Never worse"): an action is kept only when it lowers the count
of defects and costs no completeness, no outside share and no noticeable curve boundedness or
centeredness; a re-centring must instead raise curve centeredness by ``Params.repair_centre_gain``
with no more defects and no lower boundedness, and an action on a branch outside the shape may instead
lower the outside length share by ``Params.repair_outside_gain`` with as many defects, no tunnel lost
and no piece cut off (the tally counts a branch with two edges outside once, until both are back); a
fill of a missing part is judged by the explained share it adds (docs/repair.md "Fills that pass");
otherwise it is rejected, with the reason logged."""

from __future__ import annotations

import numpy as np

from ..params import Params
from .findings import Findings

__all__ = ["verdict", "worse", "recentred", "kept_part", "own_part", "KEPT_WHOLE", "FILL"]

#: the defect code of a fill of a missing part (a new stretch of curve, nothing of the curve removed)
FILL = "incomplete"

#: the defects an outside action that lowers the outside share may not add: a tunnel's cycle lost (a
#: chord through a torus's hole deleted) or a piece cut off; a spur for a spurious cycle is a fair trade
KEPT_WHOLE = ("missing_cycles", "components")


def verdict(before: Findings, after: Findings, params: Params, recentring: bool = False,
            outside: bool = False, kept: np.ndarray | None = None) -> str | None:
    """None when ``after`` may replace ``before``; else why not (one phrase). ``recentring``: the
    action only moved vertices to their cross-sections' centres; ``outside``: it answered an
    ``outside`` defect (docs/repair.md "Never worse"); ``kept``: a fill, the edges of the curve after
    it that were there before (per edge, bool), on which curve centeredness is judged
    (:func:`kept_part`, docs/repair.md "Fills that pass")."""
    b, a = before.measures, after.measures
    if kept is not None:
        a = kept_part(a, after.sample_edge, after.sample_c, kept, params)
    why = worse(b, a, params)
    if why:
        return "worse: " + "; ".join(why)
    if recentring:  # a gain of its own whatever the count: what the first look decides (screen.py)
        why = recentred(b, a, params)
        if why is None and after.total > before.total:
            why = f"no progress: {before.total} defect(s) before, {after.total} after"
        return why
    if kept is not None:
        return _filled(before, after)
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


def kept_part(a: dict, sample_edge: np.ndarray, sample_c: np.ndarray, kept: np.ndarray, params: Params) -> dict:
    """The measures ``a`` of a curve after a fill with curve centeredness counted on the samples of the
    ``kept`` edges (those there before) alone, as the curve's own: the share of them with c > c*
    (docs/metrics.md 3.3). The new stretch's own centeredness is no loss: a missing region holds only
    the unexplained side of a tube, so its skeleton runs off the axis, and centring it on the whole
    cloud's cross-sections lowered GT F1 on the tuning neurons (docs/repair.md "Fills that pass")."""
    return {**a, "centeredness": _centred(sample_edge, sample_c, np.asarray(kept, bool), params)}


def own_part(sample_edge: np.ndarray, sample_c: np.ndarray, kept: np.ndarray, params: Params) -> float | None:
    """Curve centeredness of a fill's own stretch: the share of the samples on the edges not ``kept``
    (the new ones) with c > c* (docs/metrics.md 3.3); None without a sample. Logged, not judged: on
    the tuning neurons the kept fills' own stretches are 0.0-0.33 centred, the broken hammer's tangle
    0.01-0.05 (docs/repair.md "A thick part's fill")."""
    return _centred(sample_edge, sample_c, ~np.asarray(kept, bool), params)


def _centred(sample_edge: np.ndarray, sample_c: np.ndarray, on_edge: np.ndarray, params: Params) -> float | None:
    on = on_edge[np.asarray(sample_edge, np.int64)]
    c = np.asarray(sample_c, float)[on]
    c = c[np.isfinite(c)]
    return float(np.count_nonzero(c > params.c_star) / len(c)) if len(c) else None


def _filled(before: Findings, after: Findings) -> str | None:
    """A fill is progress when it explains more of the cloud (completeness up), leaves less of it in
    counted missing parts (their share down: a region filled in part may leave two smaller pieces,
    both counted) and adds no defect of another kind (a spur, a cycle, an outside branch...)."""
    more = [k for k in before.tally if k != "missing_parts" and after.tally[k] > before.tally[k]]
    if more:
        return "no progress: more " + ", ".join(f"{k} ({before.tally[k]} -> {after.tally[k]})" for k in more)
    cb, ca = before.measures["completeness"], after.measures["completeness"]
    sb = before.missing.missing_share if before.missing is not None else None
    sa = after.missing.missing_share if after.missing is not None else None
    if cb is None or ca is None or not ca > cb or sb is None or sa is None or not sa < sb:
        return f"no progress: completeness {_r(cb)} -> {_r(ca)}, missing share {_r(sb)} -> {_r(sa)}"
    return None


def _r(x: float | None) -> float | None:
    return None if x is None else round(x, 4)
