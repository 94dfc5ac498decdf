"""The validity study's statistics (docs/validity.md): per metric and defect, the
detection AUC (defective against clean) and the Spearman correlation with the ground-truth error.

Each metric is oriented to a "badness" b (higher = worse) from its ``better`` direction: the
column's in :data:`skelcore.scores.SCORE_COLUMNS` where it has one, else this module's table
(:data:`METRICS`); a signed count (the cycle count error) is taken as |x|, a ratio that is best at 1
(the length ratio) as |log x|. Then

- AUC = P(b_defective > b_clean) + P(=) / 2 (Mann-Whitney), over every clean row and every defective
  row (all levels, shapes and seeds) of the shapes the defect applies to; NaN values are left out,
  and with fewer than two values on either side the AUC is NaN. 0.5 = blind, 1 = always worse on
  the defective skeleton, below 0.5 = better on it (the metric rewards the defect).
- Spearman rho between b and the ground-truth error (``gt_error`` = 1 - the ground-truth F1, F1
  averaged over thresholds up to one local radius) over the same rows (ties averaged; NaN when
  either is constant).
- A paper metric is **blind** to a defect when its AUC lies within 0.5 +- 0.1 (:data:`BLIND`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Iterable

import numpy as np

from ..scores import COLUMN

__all__ = ["MetricSpec", "METRICS", "BLIND", "badness", "auc", "spearman", "validity_table", "blind_spots"]

#: |AUC - 0.5| <= BLIND: the metric cannot see the defect
BLIND = 0.1


@dataclass(frozen=True)
class MetricSpec:
    key: str
    label: str
    group: str  # "paper", "skelscope", "diagnostics", "ground truth"
    orient: str  # "higher" (better), "lower", "abs" (|x| lower), "abslog" (|log x| lower)


def _col(key: str, label: str | None = None) -> MetricSpec:
    c = COLUMN[key]
    group = {"reference": "ground truth"}.get(c.group, c.group)
    return MetricSpec(key, label or c.label, group, c.better or "lower")


#: the metrics of the study, in the table's order
METRICS: tuple[MetricSpec, ...] = (
    _col("d_B"), _col("d_Wp"),
    _col("boundedness_skeletal"), _col("boundedness_curve"),
    _col("centeredness_skeletal"), _col("centeredness_curve"),
    _col("smoothness_skeletal"), _col("smoothness_curve"),
    _col("coverage_skeletal"), _col("coverage_curve"),
    _col("completeness_skeletal"), _col("completeness_curve"),
    _col("spurious_branches"), _col("spurious_length_share"), _col("spurious_cycles"), _col("missing_cycles"),
    _col("outside_length_share"), MetricSpec("n_warnings", "warnings (count)", "diagnostics", "lower"),
    *(MetricSpec(f"warn_{c}", f"warning {c}", "diagnostics", "lower")
      for c in ("incomplete", "spurious_branches", "spurious_cycles", "missing_cycles", "outside", "collapse")),
    MetricSpec("gt_f1", "GT F1", "ground truth", "higher"),
    MetricSpec("gt_precision", "GT precision", "ground truth", "higher"),
    MetricSpec("gt_recall", "GT recall", "ground truth", "higher"),
    MetricSpec("gt_chamfer_radii", "GT Chamfer (radii)", "ground truth", "lower"),
    MetricSpec("gt_junction_precision", "GT junction precision", "ground truth", "higher"),
    MetricSpec("gt_junction_recall", "GT junction recall", "ground truth", "higher"),
    MetricSpec("gt_endpoint_precision", "GT endpoint precision", "ground truth", "higher"),
    MetricSpec("gt_endpoint_recall", "GT endpoint recall", "ground truth", "higher"),
    MetricSpec("gt_cycle_error", "GT cycle error (abs)", "ground truth", "abs"),
    MetricSpec("gt_length_ratio", "GT log length ratio (abs)", "ground truth", "abslog"),
    MetricSpec("gt_splits", "GT splits", "ground truth", "lower"),
    MetricSpec("gt_merges", "GT merges", "ground truth", "lower"),
)


def badness(values: Iterable[Any], orient: str) -> np.ndarray:
    """The values oriented so that higher is worse (NaN kept)."""
    x = np.array([np.nan if v is None or v == "" else float(v) for v in values], dtype=float)
    if orient == "higher":
        return -x
    if orient == "lower":
        return x
    if orient == "abs":
        return np.abs(x)
    if orient == "abslog":
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.abs(np.log(x))
    raise ValueError(f"unknown orientation {orient!r}")


def _ranks(x: np.ndarray) -> np.ndarray:
    """Ranks 1..n, ties given their average rank."""
    _, inverse, counts = np.unique(x, return_inverse=True, return_counts=True)
    upper = np.cumsum(counts)
    return (upper - (counts - 1) / 2.0)[inverse]


def auc(bad_defective: np.ndarray, bad_clean: np.ndarray) -> float:
    """P(defective worse than clean) + ties / 2, NaN values left out; NaN with fewer than 2 a side."""
    a = np.asarray(bad_defective, float)
    b = np.asarray(bad_clean, float)
    a, b = a[~np.isnan(a)], b[~np.isnan(b)]
    if len(a) < 2 or len(b) < 2:
        return float("nan")
    ranks = _ranks(np.concatenate([a, b]))
    u = ranks[: len(a)].sum() - len(a) * (len(a) + 1) / 2
    return float(u / (len(a) * len(b)))


def spearman(x: np.ndarray, y: np.ndarray) -> float:
    """Spearman's rho of the pairs where both are numbers (NaN when fewer than 3 or one is constant)."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    ok = ~(np.isnan(x) | np.isnan(y))
    x, y = x[ok], y[ok]
    if len(x) < 3 or np.ptp(x) == 0 or np.ptp(y) == 0:
        return float("nan")
    rx, ry = _ranks(x), _ranks(y)
    return float(np.corrcoef(rx, ry)[0, 1])


def validity_table(rows: list[dict[str, Any]], metrics: tuple[MetricSpec, ...] = METRICS) -> list[dict[str, Any]]:
    """One record per (metric, defect): auc, spearman, n_clean, n_defective (and the levels' AUCs,
    ``auc_levels``, mild to strong), for every defect present in ``rows``."""
    from .skeleton_defects import DEFECTS

    present = {r["defect"] for r in rows}
    defects = [d for d in DEFECTS if d in present] + sorted(present - set(DEFECTS) - {"clean"})
    clean = [r for r in rows if r["defect"] == "clean"]
    out = []
    for d in defects:
        bad_rows = [r for r in rows if r["defect"] == d]
        shapes = {r["shape"] for r in bad_rows}
        clean_d = [r for r in clean if r["shape"] in shapes]
        levels = sorted({int(r["level_index"]) for r in bad_rows})
        both = clean_d + bad_rows
        err = np.array([float(r["gt_error"]) for r in both])
        for m in metrics:
            b_clean = badness((r.get(m.key) for r in clean_d), m.orient)
            b_bad = badness((r.get(m.key) for r in bad_rows), m.orient)
            per_level = []
            for lv in levels:
                sel = [r for r in bad_rows if int(r["level_index"]) == lv]
                per_level.append(auc(badness((r.get(m.key) for r in sel), m.orient), b_clean))
            out.append({"metric": m.key, "label": m.label, "group": m.group, "defect": d,
                        "auc": auc(b_bad, b_clean), "spearman": spearman(np.concatenate([b_clean, b_bad]), err),
                        "n_clean": int(np.count_nonzero(~np.isnan(b_clean))),
                        "n_defective": int(np.count_nonzero(~np.isnan(b_bad))), "auc_levels": per_level})
    return out


def blind_spots(table: list[dict[str, Any]], group: str = "paper") -> dict[str, list[str]]:
    """Per metric of ``group``: the defects it cannot see (AUC within 0.5 +- BLIND; a NaN AUC, no
    value on one side, is not counted)."""
    out: dict[str, list[str]] = {}
    for rec in table:
        if rec["group"] != group:
            continue
        a = rec["auc"]
        out.setdefault(rec["metric"], [])
        if not math.isnan(a) and abs(a - 0.5) <= BLIND + 1e-12:
            out[rec["metric"]].append(rec["defect"])
    return out
