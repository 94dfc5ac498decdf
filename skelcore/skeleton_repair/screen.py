"""A candidate's cheap first look (docs/repair.md "Never worse"): the edited curve's update without its
diagnostics (curve boundedness and centeredness), then its coverage and completeness alone (read from
the coverage, the missing parts' regions found only for an action that passes). An action these
already make worse is rejected without the curve's defects, the dear part of an update at 100k
points, and a re-centring without its own gain (:func:`.guard.recentred`) before its coverage too;
one that passes gets the whole update (:meth:`~skelcore.Evaluation.complete_update`). The measures
are those the whole update gives (the same stages on the same inputs, computed once), so the
decisions are the never-worse rule's own. The first look leaves out the real-scan trust checks too
(:func:`first_update`): it reads no warning; so does the whole update (:func:`whole_update`) when
they cannot change its measures, and the repair's last Evaluation gets them (:func:`with_scan_checks`;
docs/repair.md "The repair's cost")."""

from __future__ import annotations

from typing import Callable

import numpy as np

from ..curve import CurveSkeleton
from ..diagnostics.missing_parts import completeness_alone, explained_alone
from ..edit.incremental import LEFT_OUT, compute_left_out
from ..evaluation import Evaluation
from ..params import Params
from ..stages.catalogue import CATALOGUE
from .findings import Findings
from .guard import kept_part, own_part, recentred, worse
from .outside_look import outside_named, outside_of

__all__ = ["first_look", "first_update", "whole_update", "with_scan_checks", "SCAN_CHECKS", "OUTSIDE_FIRST",
           "COMPLETENESS_ALONE", "explained"]

#: whether every update of a candidate runs the real-scan trust checks (the openings' search): False,
#: since the rule reads none of their warnings; True gives the slower path, the same decisions, log and
#: curve (tests/engine/test_repair_cost.py)
SCAN_CHECKS = False
#: whether a fill's first look runs the outside test (:mod:`.outside_look`) and refuses a fill that adds an
#: outside branch without its whole update: True; False gives the slower path, the same decisions and
#: curve, the refusal logged with every defect (tests/engine/test_repair_outside_look.py)
OUTSIDE_FIRST = True
#: whether a first look reads the completeness from the coverage alone and finds the missing parts'
#: regions only for an action that passes it (:func:`_completeness`): True; False finds them at every
#: first look, the slower path, the same log and curve (tests/engine/test_repair_screen.py)
COMPLETENESS_ALONE = True
_MISSING = next(s for s in CATALOGUE if s.name == "curve missing parts")


def _num(x: object) -> float | None:
    return None if x is None or not np.isfinite(float(x)) else float(x)  # type: ignore[arg-type]


def _missing_left_out(pre: Evaluation) -> bool:
    """Whether ``pre`` (an update left without diagnostics) left out its curve missing parts, a stage
    that applies: then the first look finds its completeness."""
    ctx = getattr(pre.source, "ctx", None)
    return ctx is not None and _MISSING.applies(ctx) and ctx.not_computed.get(_MISSING.name) == LEFT_OUT


def _completeness(pre: Evaluation) -> tuple[bool, float | None]:
    """(whether it could be computed, the curve's completeness) of an update left without
    diagnostics, as the whole update's stages compute it: the coverage (kept in ``pre``), then the
    completeness the missing parts stage gives from it (:func:`completeness_alone`) without finding
    the regions, which only the whole update reads (:func:`_with_missing_parts` adds them to an
    action that passes; :data:`COMPLETENESS_ALONE` False: found here, the slower path). When that
    stage would compute the coverage again (an element in the air), it runs here whole."""
    if not _missing_left_out(pre):
        return False, None
    ctx = pre.source.ctx
    compute_left_out(pre, ("curve coverage",))
    cov = ctx.results.get("curve coverage")
    if COMPLETENESS_ALONE and cov is not None:
        alone = completeness_alone(ctx.cloud_n, ctx.curve_n, cov, ctx.params, ctx.solid_test())
        if alone is not None:
            return True, _num(alone)
    return True, _num(getattr(_with_missing_parts(pre), "completeness", None))


def explained(ev: Evaluation) -> np.ndarray | None:
    """The curve missing parts' verdict per cloud point (what completeness is the share of) of ``ev``,
    also of a first look that read its completeness alone (the coverage's, :func:`explained_alone`:
    the verdict the stage gives); None when unknown."""
    ctx = getattr(ev.source, "ctx", None)
    mp = None if ctx is None else ctx.results.get(_MISSING.name)
    if mp is not None:
        return np.asarray(mp.explained, bool)
    cov = None if ctx is None else ctx.results.get("curve coverage")
    if cov is None or not _missing_left_out(ev):
        return None
    return explained_alone(ctx.cloud_n, ctx.curve_n, cov, ctx.params, ctx.solid_test())


def _with_missing_parts(pre: Evaluation) -> object:
    """``pre``'s curve missing parts, computed in its context when left out (as the whole update's
    stage computes them, so that :meth:`~skelcore.Evaluation.complete_update` adds only the defects)."""
    ctx = pre.source.ctx
    if _missing_left_out(pre):
        compute_left_out(pre, (_MISSING.name,))
    return ctx.results.get(_MISSING.name)


def first_update(ev: Evaluation, curve: CurveSkeleton) -> Evaluation:
    """``ev``'s update to the candidate ``curve`` without its diagnostics (curve boundedness and
    centeredness), and without the real-scan trust checks unless :data:`SCAN_CHECKS`."""
    return ev.update(curve, diagnostics=False, scan_checks=SCAN_CHECKS)


def _may_find_again(pre: Evaluation) -> bool:
    """Whether the real-scan checks may change the measures of ``pre``'s whole update: an
    ``open_surface`` warning makes the missing parts be found again when some element was left out as
    outside (``outside_elements``; :func:`skelcore.stages.orchestrate.finish`); else they only add
    warnings, which the rule does not read. True when the curve's missing parts are not known yet."""
    ctx = getattr(pre.source, "ctx", None)
    if ctx is None or "curve missing parts" not in ctx.results:
        return True
    return any(getattr(ctx.results.get(f"{kind} missing parts"), "outside_elements", 0)
               for kind in ("skeletal", "curve"))


def whole_update(pre: Evaluation, cancel: Callable[[], bool] | None = None) -> tuple[Evaluation, bool]:
    """(``pre``'s :meth:`~skelcore.Evaluation.complete_update`, whether it ran the real-scan trust
    checks): left out unless :data:`SCAN_CHECKS` or they may change its measures."""
    scan = SCAN_CHECKS or _may_find_again(pre)
    return pre.complete_update(cancel, scan_checks=scan), scan


def with_scan_checks(ev: Evaluation, curve: CurveSkeleton) -> Evaluation:
    """``ev`` (the Evaluation of ``curve``, made by :func:`whole_update` without the real-scan trust
    checks) with them: its update to the same curve, the same scores and defects and every warning."""
    return ev.update(curve)


def first_look(before: Findings, pre: Evaluation, params: Params, recentring: bool = False,
               kept: np.ndarray | None = None) -> tuple[dict[str, float | None], str | None]:
    """:func:`_judged`; an action that passes gets its curve missing parts now (the regions, left out
    while only its completeness was read), so that its whole update adds the defects alone."""
    a, why = _judged(before, pre, params, recentring, kept)
    if why is None and COMPLETENESS_ALONE:
        _with_missing_parts(pre)
    return a, why


def _judged(before: Findings, pre: Evaluation, params: Params, recentring: bool,
            kept: np.ndarray | None) -> tuple[dict[str, float | None], str | None]:
    """(the measures known without defects, why the action is worse or None) for ``pre``, the
    candidate's ``update(..., diagnostics=False)``: completeness, curve boundedness and centeredness
    against ``before`` with the bounds of :func:`.guard.verdict`; the outside share stays None.
    ``recentring``: a re-centring, refused before its completeness when it has not its gain;
    ``kept``: a fill, curve centeredness judged on these edges (:func:`.guard.kept_part`), and, with
    :data:`OUTSIDE_FIRST`, its outside share and outside branches (:mod:`.outside_look`): one that adds
    an outside branch is refused, the reason naming them (docs/repair.md "The repair's cost"); the
    centeredness of its own stretch is given (``fill_centeredness``, :func:`.guard.own_part`)."""
    s = pre.summary()
    a = {"completeness": None, "outside_share": None,
         "boundedness": _num(s["boundedness"]["curve"]), "centeredness": _num(s["centeredness"]["curve"])}
    if recentring and (why_not := recentred(before.measures, a, params)) is not None:
        return a, why_not
    known, a["completeness"] = _completeness(pre)
    judged = a
    if kept is not None and pre.curve is not None:
        cl = pre.curve
        sample_c = cl.sample_centeredness(params.beta_star)
        judged = kept_part(a, cl.sample_edge, sample_c, kept, params)
        a["fill_centeredness"] = own_part(cl.sample_edge, sample_c, kept, params)
    why = worse(before.measures, judged, params, completeness=known)
    if why or kept is None or not OUTSIDE_FIRST or (out := outside_of(pre)) is None:
        return a, ("worse: " + "; ".join(why)) if why else None
    a["outside_share"] = judged["outside_share"] = out.length_share
    why = worse(before.measures, judged, params, completeness=known)
    if why:  # the outside share, the one measure not judged above
        return a, "worse: " + "; ".join(why)
    n_before, n_after = before.tally["outside"], len(out.defective_branches())
    if n_after > n_before:  # the rule refuses a fill that adds a defect of another kind (guard._filled)
        return a, f"no progress: more outside ({n_before} -> {n_after}): {outside_named(out, np.flatnonzero(~np.asarray(kept, bool)))}"
    return a, None

