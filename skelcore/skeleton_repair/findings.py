"""What the judge found, read once per Evaluation for the repair (docs/repair.md): the measures the
never-worse rule compares and the defects the actions answer, from the evaluation's diagnostics."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..evaluation import Evaluation

__all__ = ["Findings", "read_findings", "MEASURES", "TALLIED"]

#: the measures of an Evaluation the never-worse rule watches (None when not computed)
MEASURES = ("completeness", "outside_share", "boundedness", "centeredness")
#: the defect counts whose sum must go down for an action to count as progress
TALLIED = ("spurious_branches", "spurious_cycles", "outside", "components", "missing_cycles", "missing_parts")


@dataclass
class Findings:
    """``measures``: :data:`MEASURES`; ``tally``: the count of each :data:`TALLIED` defect;
    ``defects``: the evaluation's :class:`~skelcore.diagnostics.defects.CurveDefects`; ``warnings``:
    the warning codes; ``missing``: the curve's missing parts; ``sample_edge``, ``sample_beta``, ``sample_c``, ``sample_t``: the curve samples' edge,
    local boundedness / centeredness and place on the edge (what an action's "why" quotes and the weakest edge is chosen by)."""

    measures: dict[str, float | None]
    tally: dict[str, int]
    defects: Any
    warnings: list[str]
    missing: Any = None
    sample_edge: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    sample_beta: np.ndarray = field(default_factory=lambda: np.zeros(0))
    sample_c: np.ndarray = field(default_factory=lambda: np.zeros(0))
    sample_t: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def total(self) -> int:
        return int(sum(self.tally.values()))

    def local(self, edges: np.ndarray) -> dict[str, float | None]:
        """Mean local boundedness and centeredness of the samples on these edge ids (None: no sample)."""
        on = np.isin(self.sample_edge, np.asarray(edges, np.int64))
        if not on.any():
            return {"boundedness": None, "centeredness": None}
        c = self.sample_c[on]
        c = c[np.isfinite(c)]
        return {"boundedness": round(float(np.mean(self.sample_beta[on])), 4),
                "centeredness": round(float(np.mean(c)), 4) if len(c) else None}


def _num(x: Any) -> float | None:
    return None if x is None or not np.isfinite(float(x)) else float(x)


def read_findings(ev: Evaluation) -> Findings:
    """The findings of ``ev`` (an evaluation of a curve skeleton with its diagnostics)."""
    s = ev.summary()
    # two keys of the diagnostics' summary, not the whole (its per-branch lists: skelcore/diagnostics/record.py)
    diag = ev.diagnostics
    outside = (diag.part("outside") if diag is not None else None) or {}
    completeness = (diag.part("completeness") if diag is not None else None) or {}
    measures = {"completeness": _num(completeness.get("curve")),
                "outside_share": _num(outside.get("length_share")),
                "boundedness": _num(s["boundedness"]["curve"]),
                "centeredness": _num(s["centeredness"]["curve"])}
    ctx = getattr(ev.source, "ctx", None)
    defects = None if ctx is None else ctx.results.get("curve defects")
    tally = dict.fromkeys(TALLIED, 0)
    if defects is not None:
        br = defects.branches
        tally["spurious_branches"] = int(len(defects.spurs.spurious))
        tally["spurious_cycles"] = int(len(defects.cycles.spurious))
        tally["missing_cycles"] = int(defects.cycles.missing)
        tally["outside"] = int(len(defects.outside.defective_branches()))
        tally["components"] = int(br.n_components) - 1 - sum(k == "point" for k in br.kind)
    missing = None if ctx is None else ctx.results.get("curve missing parts")
    if missing is not None:
        tally["missing_parts"] = len(missing.counted)
    cl = ev.curve
    beta = np.asarray(cl.sample_boundedness, float) if cl is not None else np.zeros(0)
    c = np.asarray(cl.sample_centeredness(ev.params.beta_star), float) if cl is not None else np.zeros(0)
    edge = np.asarray(cl.sample_edge, np.int64) if cl is not None else np.zeros(0, np.int64)
    t = np.asarray(cl.sample_t, float) if cl is not None else np.zeros(0)
    return Findings(measures, tally, defects, [w.code for w in ev.warnings], missing, edge, beta, c, t)
