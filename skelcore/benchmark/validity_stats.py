"""The validity study's statistics (docs/validity.md "Statistics"), from scipy.stats.

Each metric is oriented to a "badness" b (higher = worse): its ``better`` direction in
:data:`skelcore.scores.SCORE_COLUMNS` where it has one, else :data:`METRICS`' (|x| for a signed
error, |log x| for a ratio best at 1). Per metric and defect:

- pooled AUC = P(b_defective > b_clean) + P(=) / 2 (``mannwhitneyu``'s U / (n1 n2)), all levels;
- paired AUC = P(b_defective > b_clean of the same shape and seed) + P(=) / 2, the effect (mean
  paired difference of b) and the Wilcoxon signed-rank p-value (``wilcoxon``, zeros split);
- 95 % percentile intervals of both AUCs and the effect by ``bootstrap`` over (shape, seed)
  clusters (the levels of one shape and seed share their clean skeleton, so they are resampled
  together);
- Spearman rho (``spearmanr``) between b and the ground-truth error 1 - F1;
- a metric is **blind** to a defect when the paired AUC's interval holds 0.5 (:func:`is_blind`).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any, Callable, Iterable

import numpy as np
from scipy.stats import bootstrap, mannwhitneyu, spearmanr, wilcoxon

from ..scores import COLUMN

__all__ = ["MetricSpec", "METRICS", "BLIND", "CONFIDENCE", "RESAMPLES", "badness", "auc", "spearman",
           "cluster_interval", "validity_table", "is_blind", "blind_spots"]

#: without intervals, |AUC - 0.5| <= BLIND: the metric cannot see the defect (the former rule)
BLIND = 0.1
#: the bootstrap intervals' confidence level and number of resamples
CONFIDENCE = 0.95
RESAMPLES = 2000


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
    # the other communities' (docs/metrics.md 5.3.2); ESA is the Chamfer distance over the diagonal
    *(MetricSpec(f"gt_diag_f1_{k}", f"GT F1 at {k} % diag", "ground truth", "higher") for k in (1, 2, 5)),
    MetricSpec("gt_branch_precision", "GT branch precision", "ground truth", "higher"),
    MetricSpec("gt_branch_recall", "GT branch recall", "ground truth", "higher"),
    MetricSpec("gt_branch_f1", "GT branch F1", "ground truth", "higher"),
    MetricSpec("gt_dup_precision", "GT duplicate-aware precision", "ground truth", "higher"),
    MetricSpec("gt_betti0_error", "GT Betti-0 error (abs)", "ground truth", "abs"),
    MetricSpec("gt_betti1_error", "GT Betti-1 error (abs)", "ground truth", "abs"),
    MetricSpec("gt_radius_error", "GT radius error", "ground truth", "lower"),
    MetricSpec("gt_esa", "GT ESA (diag)", "ground truth", "lower"),
    MetricSpec("gt_dsa", "GT DSA (diag)", "ground truth", "lower"),
    MetricSpec("gt_pds", "GT PDS", "ground truth", "lower"),
    MetricSpec("gt_path_f1", "GT path F1", "ground truth", "higher"),
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


def auc(bad_defective: np.ndarray, bad_clean: np.ndarray) -> float:
    """P(defective worse than clean) + ties / 2, NaN values left out; NaN with fewer than 2 a side
    (scipy's Mann-Whitney U of the defective side over n_defective x n_clean)."""
    a, b = _finite(bad_defective), _finite(bad_clean)
    if len(a) < 2 or len(b) < 2:
        return float("nan")
    return float(mannwhitneyu(a, b, alternative="two-sided").statistic / (len(a) * len(b)))


def spearman(x: np.ndarray, y: np.ndarray) -> float:
    """Spearman's rho of the pairs where both are numbers (NaN when fewer than 3 or one is constant)."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    ok = ~(np.isnan(x) | np.isnan(y))
    x, y = x[ok], y[ok]
    if len(x) < 3 or np.ptp(x) == 0 or np.ptp(y) == 0:
        return float("nan")
    return float(spearmanr(x, y).statistic)


def _finite(x: Any) -> np.ndarray:
    x = np.asarray(x, float)
    return x[~np.isnan(x)]


def cluster_interval(statistic: Callable[[np.ndarray], np.ndarray], n_clusters: int,
                     seed: int = 0) -> tuple[float, float]:
    """Percentile bootstrap interval (:data:`CONFIDENCE`, :data:`RESAMPLES`; scipy.stats.bootstrap)
    of a statistic of cluster multiplicities: ``statistic(M)`` maps a (B, C) count matrix (how often
    each of the C clusters was drawn) to B values. NaN draws are left out; (NaN, NaN) below 2 clusters."""
    if n_clusters < 2:
        return float("nan"), float("nan")

    def stat(idx: np.ndarray, axis: int = -1) -> np.ndarray:
        idx = np.moveaxis(np.asarray(idx, np.int64), axis, -1)
        flat = idx.reshape(-1, idx.shape[-1])
        counts = np.zeros((len(flat), n_clusters))
        np.add.at(counts, (np.repeat(np.arange(len(flat)), flat.shape[1]), flat.ravel()), 1.0)
        return statistic(counts).reshape(idx.shape[:-1])

    with warnings.catch_warnings(), np.errstate(invalid="ignore", divide="ignore"):
        warnings.simplefilter("ignore")
        res = bootstrap((np.arange(n_clusters),), stat, vectorized=True, n_resamples=RESAMPLES,
                        confidence_level=CONFIDENCE, method="percentile", rng=np.random.default_rng(seed))
        lo, hi = float(res.confidence_interval.low), float(res.confidence_interval.high)
        if np.isnan(lo) or np.isnan(hi):
            dist = res.bootstrap_distribution
            if np.isnan(dist).all():
                return float("nan"), float("nan")
            alpha = (1 - CONFIDENCE) / 2
            lo, hi = (float(np.nanquantile(dist, q)) for q in (alpha, 1 - alpha))
    return lo, hi


def _pooled(b_bad: np.ndarray, c_bad: np.ndarray, b_clean: np.ndarray, c_clean: np.ndarray, n: int):
    """AUC (defective vs clean, pooled) and its cluster-bootstrap interval."""
    ok_b, ok_c = ~np.isnan(b_bad), ~np.isnan(b_clean)
    b_bad, c_bad, b_clean, c_clean = b_bad[ok_b], c_bad[ok_b], b_clean[ok_c], c_clean[ok_c]
    value = auc(b_bad, b_clean)
    if np.isnan(value):
        return value, (float("nan"), float("nan"))
    g = (b_bad[:, None] > b_clean[None, :]) + 0.5 * (b_bad[:, None] == b_clean[None, :])
    s = np.zeros((n, n))
    np.add.at(s, (np.repeat(c_bad, len(c_clean)), np.tile(c_clean, len(c_bad))), g.ravel())
    nd, nc = np.bincount(c_bad, minlength=n), np.bincount(c_clean, minlength=n)

    def stat(m: np.ndarray) -> np.ndarray:
        return np.einsum("bi,ij,bj->b", m, s, m) / ((m @ nd) * (m @ nc))

    return value, cluster_interval(stat, n)


def _paired(delta: np.ndarray, cluster: np.ndarray, n: int) -> dict[str, Any]:
    """Paired AUC P(delta > 0) + P(= 0) / 2, the mean paired difference, their cluster-bootstrap
    intervals, and the Wilcoxon signed-rank p-value (scipy.stats.wilcoxon, zeros split)."""
    ok = ~np.isnan(delta)
    delta, cluster = delta[ok], cluster[ok]
    nan2 = (float("nan"), float("nan"))
    if len(delta) == 0:
        return {"auc_paired": float("nan"), "auc_paired_ci": nan2, "effect": float("nan"), "effect_ci": nan2,
                "wilcoxon_p": float("nan"), "n_pairs": 0}
    win = (delta > 0) + 0.5 * (delta == 0)
    w, d, t = (np.bincount(cluster, weights=x, minlength=n) for x in (win, delta, np.ones(len(delta))))
    p = float("nan")
    if np.any(delta != 0) and len(delta) >= 2:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            p = float(wilcoxon(delta, zero_method="zsplit").pvalue)
    return {"auc_paired": float(win.mean()), "auc_paired_ci": cluster_interval(lambda m: (m @ w) / (m @ t), n),
            "effect": float(delta.mean()), "effect_ci": cluster_interval(lambda m: (m @ d) / (m @ t), n, seed=1),
            "wilcoxon_p": p, "n_pairs": int(len(delta))}


def validity_table(rows: list[dict[str, Any]], metrics: tuple[MetricSpec, ...] = METRICS) -> list[dict[str, Any]]:
    """One record per (metric, defect): auc (pooled) and its interval ``auc_ci``, the paired analysis
    (each defective skeleton against the clean one of its shape and seed: ``auc_paired`` and
    interval, ``effect`` = mean paired difference of the badness and interval, ``wilcoxon_p``,
    ``n_pairs``), spearman, n_clean, n_defective and ``auc_levels`` (mild to strong); intervals are
    bootstraps over (shape, seed) clusters. Every defect present in ``rows``."""
    from .skeleton_defects import DEFECTS

    present = {r["defect"] for r in rows}
    defects = [d for d in DEFECTS if d in present] + sorted(present - set(DEFECTS) - {"clean"})
    clean = [r for r in rows if r["defect"] == "clean"]
    out = []
    for d in defects:
        bad_rows = [r for r in rows if r["defect"] == d]
        units = {(r["shape"], str(r["seed"])) for r in bad_rows}
        clean_d = [r for r in clean if (r["shape"], str(r["seed"])) in units] or \
            [r for r in clean if r["shape"] in {u[0] for u in units}]
        ids = {u: i for i, u in enumerate(sorted(units | {(r["shape"], str(r["seed"])) for r in clean_d}))}
        c_bad = np.array([ids[(r["shape"], str(r["seed"]))] for r in bad_rows], np.int64)
        c_clean = np.array([ids[(r["shape"], str(r["seed"]))] for r in clean_d], np.int64)
        partner = {(r["shape"], str(r["seed"])): r for r in clean_d}
        levels = sorted({int(r["level_index"]) for r in bad_rows})
        both = clean_d + bad_rows
        err = np.array([float(r["gt_error"]) for r in both])
        for m in metrics:
            b_clean = badness((r.get(m.key) for r in clean_d), m.orient)
            b_bad = badness((r.get(m.key) for r in bad_rows), m.orient)
            b_partner = badness((partner.get((r["shape"], str(r["seed"])), {}).get(m.key) for r in bad_rows), m.orient)
            per_level = []
            for lv in levels:
                sel = [r for r in bad_rows if int(r["level_index"]) == lv]
                per_level.append(auc(badness((r.get(m.key) for r in sel), m.orient), b_clean))
            value, ci = _pooled(b_bad, c_bad, b_clean, c_clean, len(ids))
            rec = {"metric": m.key, "label": m.label, "group": m.group, "defect": d, "auc": value, "auc_ci": ci,
                   **_paired(b_bad - b_partner, c_bad, len(ids)),
                   "spearman": spearman(np.concatenate([b_clean, b_bad]), err),
                   "n_clean": int(np.count_nonzero(~np.isnan(b_clean))),
                   "n_defective": int(np.count_nonzero(~np.isnan(b_bad))), "auc_levels": per_level}
            out.append(rec)
    return out


def is_blind(rec: dict[str, Any]) -> bool:
    """Blind: the paired AUC's interval holds 0.5 (the pooled AUC's when there are no pairs); an
    interval that cannot be drawn (NaN) says nothing."""
    lo, hi = rec.get("auc_paired_ci", (float("nan"),) * 2) if rec.get("n_pairs") else rec.get("auc_ci", (float("nan"),) * 2)
    return not (math.isnan(lo) or math.isnan(hi)) and lo <= 0.5 <= hi


def blind_spots(table: list[dict[str, Any]], group: str = "paper") -> dict[str, list[str]]:
    """Per metric of ``group``: the defects it cannot see (:func:`is_blind`; a record without
    intervals falls back to its AUC within 0.5 +- :data:`BLIND`)."""
    out: dict[str, list[str]] = {}
    for rec in table:
        if rec["group"] != group:
            continue
        out.setdefault(rec["metric"], [])
        if "auc_ci" in rec or "auc_paired_ci" in rec:
            blind = is_blind(rec)
        else:
            a = rec["auc"]
            blind = not math.isnan(a) and abs(a - 0.5) <= BLIND + 1e-12
        if blind:
            out[rec["metric"]].append(rec["defect"])
    return out
