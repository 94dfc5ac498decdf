"""Does the paper's leaderboard pick the skeleton closest to the truth?

Reads a ``skelcore compare`` run folder of a ``skelcore bench make`` suite (its results.csv, whose
jobs carry the ground-truth columns, docs/compare.md "Ground truth") and prints Markdown:

- per method: jobs ok / failed, the mean of the ground-truth and of the paper's metrics (Eq. 5-9),
  and each method's rank on them (1 = best; direction from ``skelcore.scores.COLUMN``);
- per method and scan effect (the case name's ``__effect-level`` part): the mean GT F1;
- Spearman's rho between the ranking by GT F1 (and by GT Chamfer in radii) and the ranking by each
  paper metric, each oriented so that +1 means "the paper metric ranks as the truth does":
  over the methods (their means), over all jobs, and within each case (the methods ranked on one
  cloud, rho averaged over the cases where both columns vary);
- all of it again on the cases every method finished;
- the best and the worst job by GT F1, with their skeleton render (renders/KEY_skeleton.png).

    .venv/bin/python scripts/leaderboard.py RUN_DIR
"""

from __future__ import annotations

import argparse
import csv
import math
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np
from scipy.stats import spearmanr

from skelcore.scores import COLUMN

PAPER = ("d_B", "d_Wp", "boundedness_skeletal", "boundedness_curve", "centeredness_skeletal",
         "centeredness_curve", "smoothness_skeletal", "smoothness_curve")
TRUTH = ("gt_f1", "gt_chamfer_radii")
SHOWN_TRUTH = ("gt_f1", "gt_chamfer_radii", "gt_precision", "gt_recall", "gt_junction_recall",
               "gt_endpoint_recall", "gt_cycle_error", "gt_length_ratio")


def _num(v: str) -> float:
    try:
        return float(v)
    except (TypeError, ValueError):
        return math.nan


def _good(col: str, x: np.ndarray) -> np.ndarray:
    """The column turned so that larger is better (gt_length_ratio: closeness to 1)."""
    if col == "gt_length_ratio":
        return -np.abs(np.log(x))
    return -x if COLUMN[col].better == "lower" else x


def _rho(a: np.ndarray, b: np.ndarray) -> float:
    ok = np.isfinite(a) & np.isfinite(b)
    if ok.sum() < 3 or np.ptp(a[ok]) == 0 or np.ptp(b[ok]) == 0:
        return math.nan
    return float(spearmanr(a[ok], b[ok]).statistic)


def _ranks(values: dict[str, float]) -> dict[str, int]:
    """1 = best (values already oriented larger = better); NaN last."""
    order = sorted(values, key=lambda m: -values[m] if math.isfinite(values[m]) else math.inf)
    return {m: i + 1 for i, m in enumerate(order)}


def effect_of(case: str) -> str:
    """``tree_3__noise-0.05`` -> ``noise``; ``tree_3__clean`` -> ``clean``."""
    tail = case.split("__", 1)[1] if "__" in case else "clean"
    return tail.split("-", 1)[0]


def _fmt(x: float, digits: int = 3) -> str:
    return "-" if not math.isfinite(x) else f"{x:.{digits}f}"


def report(run: Path, common: bool = False) -> str:
    """The tables; ``common``: only the cases every method finished (a method that fails on the hard
    cases would otherwise be averaged over the easy ones alone)."""
    rows = list(csv.DictReader(open(run / "results.csv", newline="")))
    methods = list(dict.fromkeys(r["method"] for r in rows))
    if common:
        bad = {r["shape"] for r in rows if r["status"] != "ok"}
        rows = [r for r in rows if r["shape"] not in bad]
    ok = [r for r in rows if r["status"] == "ok"]
    cols = (*SHOWN_TRUTH, *PAPER, "seconds")
    val = {c: np.array([_num(r[c]) for r in ok]) for c in cols}
    meth = np.array([r["method"] for r in ok])
    case = np.array([r["shape"] for r in ok])
    out: list[str] = []

    # 1. per method: means and ranks
    mean = {c: {m: float(np.nanmean(val[c][meth == m])) if np.isfinite(val[c][meth == m]).any()
                else math.nan for m in methods} for c in cols}
    rank = {c: _ranks({m: float(_good(c, np.array([mean[c][m]]))[0]) for m in methods})
            for c in cols if c != "seconds"}
    fails = defaultdict(list)
    for r in rows:
        if r["status"] != "ok":
            fails[r["method"]].append(r["shape"])
    head = ["method", "ok", *cols]
    out.append("| " + " | ".join(head) + " |")
    out.append("|" + "---|" * len(head))
    for m in methods:
        n = sum(1 for r in rows if r["method"] == m)
        cells = [m, f"{(meth == m).sum()}/{n}"]
        for c in cols:
            d = 1 if c == "seconds" else (4 if c in ("d_B", "d_Wp") else 3)
            cells.append(_fmt(mean[c][m], d) + (f" ({rank[c][m]})" if c in rank else ""))
        out.append("| " + " | ".join(cells) + " |")
    for m, shapes in fails.items():
        out.append(f"\nfailed: {m}: {len(shapes)} ({', '.join(shapes)})")

    # 2. GT F1 per scan effect
    effects = list(dict.fromkeys(effect_of(s) for s in case))
    eff = np.array([effect_of(s) for s in case])
    out += ["", "| method | " + " | ".join(effects) + " |", "|---|" + "---|" * len(effects)]
    for m in methods:
        cells = [_fmt(float(np.nanmean(val["gt_f1"][(meth == m) & (eff == e)])))
                 if ((meth == m) & (eff == e)).any() else "-" for e in effects]
        out.append(f"| {m} | " + " | ".join(cells) + " |")

    # 3. Spearman: truth ranking vs each paper metric
    out += ["", "| paper metric | " + " | ".join(
        f"{t} {w}" for t in TRUTH for w in ("methods", "jobs", "within case")) + " |",
        "|---|" + "---|" * (3 * len(TRUTH))]
    for p in PAPER:
        cells = []
        for t in TRUTH:
            gm = np.array([mean[t][m] for m in methods])
            pm = np.array([mean[p][m] for m in methods])
            cells.append(_fmt(_rho(_good(t, gm), _good(p, pm)), 2))
            gt, pp = _good(t, val[t]), _good(p, val[p])
            cells.append(_fmt(_rho(gt, pp), 2))
            within = [_rho(gt[case == c], pp[case == c]) for c in dict.fromkeys(case)]
            within = [w for w in within if math.isfinite(w)]
            cells.append(f"{_fmt(float(np.mean(within)), 2)} (n={len(within)})" if within else "-")
        out.append(f"| {p} | " + " | ".join(cells) + " |")

    # 4. best and worst job by GT F1
    f1 = val["gt_f1"]
    if np.isfinite(f1).any():
        out.append("")
        for label, i in (("best", int(np.nanargmax(f1))), ("worst", int(np.nanargmin(f1)))):
            r = ok[i]
            out.append(f"{label} by gt_f1: {r['shape']} / {r['method']}: gt_f1 {_fmt(f1[i])}, "
                       f"gt_chamfer_radii {_fmt(_num(r['gt_chamfer_radii']))}, "
                       f"render {run / 'renders' / (r['key'] + '_skeleton.png')}")
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run", type=Path, help="a skelcore compare run folder (results.csv)")
    a = ap.parse_args(argv)
    if not (a.run / "results.csv").is_file():
        print(f"{a.run}: no results.csv: not a finished skelcore compare run", file=sys.stderr)
        return 2
    print(f"## all jobs\n\n{report(a.run)}\n\n## the cases every method finished\n\n"
          f"{report(a.run, common=True)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
