"""The validity study's outputs, each written atomically into the run's folder:

- ``scores.csv``: every row (shape, family, seed, defect, level, every metric, the ground truth);
- ``validity.csv``: per metric and defect the AUC, Spearman rho, counts and the AUC per level;
- ``validity.md``: the AUC table (metrics x defects, rho beside each AUC), the AUC per level of the
  paper's metrics, and per paper metric the defects it cannot see (:func:`.validity_stats.blind_spots`);
- ``validity.png``: the heat-map of AUC and rho (matplotlib, imported here only when drawing).
"""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path
from typing import Any

import numpy as np

from ..io.atomic import atomic_open
from .validity_stats import BLIND, METRICS, blind_spots, validity_table

__all__ = ["write_report", "markdown_table", "draw_heatmap", "ROW_KEYS"]

#: the leading columns of scores.csv
ROW_KEYS = ("shape", "family", "seed", "defect", "level", "level_index")


def _fmt(x: Any, digits: int = 2) -> str:
    if x is None:
        return "-"
    x = float(x)
    return "nan" if math.isnan(x) else f"{x:.{digits}f}"


def _write_text(path: Path, text: str) -> None:
    with atomic_open(path, "w") as fh:
        fh.write(text)


def _csv_text(header: list[str], rows: list[list[Any]]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    w.writerows(rows)
    return buf.getvalue()


def _defects(table: list[dict[str, Any]]) -> list[str]:
    return list(dict.fromkeys(r["defect"] for r in table))


def markdown_table(table: list[dict[str, Any]]) -> str:
    """The AUC table (rho in parentheses), the paper metrics' AUC per level and their blind spots."""
    defects = _defects(table)
    cell = {(r["metric"], r["defect"]): r for r in table}
    labels = {m.key: (m.label, m.group) for m in METRICS}
    metrics = list(dict.fromkeys(r["metric"] for r in table))
    lines = ["| metric | group | " + " | ".join(defects) + " |", "|---|---|" + "---|" * len(defects)]
    for m in metrics:
        lab, grp = labels.get(m, (m, ""))
        cells = []
        for d in defects:
            r = cell.get((m, d))
            cells.append("-" if r is None else f"{_fmt(r['auc'])} ({_fmt(r['spearman'])})")
        lines.append(f"| {lab} | {grp} | " + " | ".join(cells) + " |")
    lines += ["", "AUC per level (mild, medium, strong) for the paper's metrics and the ground-truth F1:", "",
              "| metric | " + " | ".join(defects) + " |", "|---|" + "---|" * len(defects)]
    for m in [k for k in metrics if labels.get(k, ("", ""))[1] == "paper"] + ["gt_f1"]:
        cells = []
        for d in defects:
            r = cell.get((m, d))
            cells.append("-" if r is None else " / ".join(_fmt(a) for a in r["auc_levels"]))
        lines.append(f"| {labels.get(m, (m,))[0]} | " + " | ".join(cells) + " |")
    lines += ["", f"Defects each paper metric cannot see (AUC within 0.5 +- {BLIND:g}):", ""]
    for m, blind in blind_spots(table).items():
        lines.append(f"- {labels.get(m, (m,))[0]}: {', '.join(blind) if blind else 'none'}")
    return "\n".join(lines) + "\n"


def draw_heatmap(table: list[dict[str, Any]], path: Path, title: str = "") -> None:
    """AUC (left) and Spearman rho with the ground-truth error (right), metrics x defects, annotated."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.colors import ListedColormap
    from matplotlib.figure import Figure

    from .. import colors

    defects = _defects(table)
    metrics = list(dict.fromkeys(r["metric"] for r in table))
    labels = {m.key: m.label for m in METRICS}
    cell = {(r["metric"], r["defect"]): r for r in table}
    cmap = ListedColormap(colors.lookup_table("viridis") / 255.0)
    fig = Figure(figsize=(2.0 + 0.62 * len(defects) * 2, 1.2 + 0.24 * len(metrics)), layout="constrained")
    for k, (what, lo, hi) in enumerate((("auc", 0.0, 1.0), ("spearman", -1.0, 1.0))):
        ax = fig.add_subplot(1, 2, k + 1)
        z = np.array([[float(cell[(m, d)][what]) if (m, d) in cell else np.nan for d in defects] for m in metrics])
        im = ax.imshow(np.ma.masked_invalid(z), cmap=cmap, vmin=lo, vmax=hi, aspect="auto")
        ax.set_facecolor("#dddddd")
        ax.set_xticks(range(len(defects)), [d.replace("_", " ") for d in defects], rotation=45, ha="right", fontsize=7)
        ax.set_yticks(range(len(metrics)), [labels.get(m, m) for m in metrics] if k == 0 else [], fontsize=7)
        for i in range(len(metrics)):
            for j in range(len(defects)):
                if not np.isnan(z[i, j]):
                    t = (z[i, j] - lo) / (hi - lo)
                    ax.text(j, i, f"{z[i, j]:.2f}", ha="center", va="center", fontsize=5.5,
                            color="black" if t > 0.55 else "white")
        ax.set_title("detection AUC (defective vs clean)" if what == "auc" else "Spearman rho with 1 - GT F1",
                     fontsize=8)
        fig.colorbar(im, ax=ax, fraction=0.04, pad=0.02).ax.tick_params(labelsize=6)
    if title:
        fig.suptitle(title, fontsize=8)
    with atomic_open(path, "wb") as fh:
        fig.savefig(fh, format="png", dpi=130, bbox_inches="tight")


def write_report(folder: Path, rows: list[dict[str, Any]], *, figure: bool = True,
                 note: str = "") -> list[dict[str, Any]]:
    """Write the four outputs (module docstring) for ``rows``; returns the statistics table."""
    folder = Path(folder)
    metric_keys = sorted({k for r in rows for k in r} - set(ROW_KEYS))
    _write_text(folder / "scores.csv", _csv_text([*ROW_KEYS, *metric_keys],
                                                 [[r.get(k, "") for k in ROW_KEYS] + [r.get(k) for k in metric_keys]
                                                  for r in rows]))
    table = validity_table(rows)
    _write_text(folder / "validity.csv", _csv_text(
        ["metric", "group", "defect", "auc", "spearman", "n_clean", "n_defective", "auc_levels"],
        [[r["metric"], r["group"], r["defect"], r["auc"], r["spearman"], r["n_clean"], r["n_defective"],
          " ".join(_fmt(a, 4) for a in r["auc_levels"])] for r in table]))
    head = ("# Which metric sees which defect\n\n" + (f"{note}. " if note else "") +
            f"{len(rows)} scored skeletons. Cells: detection AUC (rho = Spearman correlation with the "
            "ground-truth error 1 - F1). docs/validity.md explains both.\n\n")
    _write_text(folder / "validity.md", head + markdown_table(table))
    if figure and table:
        draw_heatmap(table, folder / "validity.png", note)
    return table
