"""The validity study's outputs, each written atomically into the run's folder:

- ``scores.csv``: every row (shape, family, seed, defect, level, every metric, the ground truth);
- ``validity.csv``: per set (the benchmark's shapes, the traced neurons), metric and defect the
  paired and pooled AUCs with their intervals, the effect, Wilcoxon's p, Spearman rho, counts and
  the AUC per level;
- ``validity.md``: per set the paired AUC table (metrics x defects, interval beside each), the
  pooled AUC (rho), the AUC per level of the paper's metrics, and per paper metric the defects it
  cannot see (:func:`.validity_stats.blind_spots`);
- ``validity.png``: the heat-map of paired AUC and rho (matplotlib, imported here only when drawing).
"""

from __future__ import annotations

import csv
import io
import math
from pathlib import Path
from typing import Any

import numpy as np

from ..io.atomic import atomic_open
from .validity_stats import METRICS, blind_spots, validity_table

__all__ = ["write_report", "markdown_table", "draw_heatmap", "ROW_KEYS", "SETS", "set_tables"]

#: the sets the report keeps apart: a row's family "neuron" is the real suite
SETS = ("shapes", "neurons")

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


def set_tables(rows: list[dict[str, Any]]) -> dict[str, list[dict[str, Any]]]:
    """The statistics table of each set present in ``rows`` (:data:`SETS`), each record with its ``set``."""
    out = {}
    for name in SETS:
        sel = [r for r in rows if (r.get("family") == "neuron") == (name == "neurons")]
        if sel:
            out[name] = [{**rec, "set": name} for rec in validity_table(sel)]
    return out


def _ci(rec: dict[str, Any], key: str) -> str:
    lo, hi = rec.get(key, (float("nan"), float("nan")))
    return f"[{_fmt(lo)}, {_fmt(hi)}]"


def markdown_table(table: list[dict[str, Any]]) -> str:
    """The paired AUC table (95 % interval beside each), the pooled AUC (rho in parentheses), the
    paper metrics' AUC per level and their blind spots."""
    defects = _defects(table)
    cell = {(r["metric"], r["defect"]): r for r in table}
    labels = {m.key: (m.label, m.group) for m in METRICS}
    metrics = list(dict.fromkeys(r["metric"] for r in table))
    def table_of(title: str, text: Any) -> list[str]:
        out = [title, "", "| metric | group | " + " | ".join(defects) + " |", "|---|---|" + "---|" * len(defects)]
        for m in metrics:
            lab, grp = labels.get(m, (m, ""))
            cells = ["-" if cell.get((m, d)) is None else text(cell[(m, d)]) for d in defects]
            out.append(f"| {lab} | {grp} | " + " | ".join(cells) + " |")
        return out

    lines = table_of("Paired AUC [95 % interval] (each defective skeleton against its shape's and seed's clean one):",
                     lambda r: f"{_fmt(r.get('auc_paired'))} {_ci(r, 'auc_paired_ci')}")
    lines += [""] + table_of("Pooled AUC [95 % interval] (Spearman rho with 1 - GT F1):",
                             lambda r: f"{_fmt(r['auc'])} {_ci(r, 'auc_ci')} ({_fmt(r['spearman'])})")
    lines += ["", "AUC per level (mild, medium, strong) for the paper's metrics and the ground-truth F1:", "",
              "| metric | " + " | ".join(defects) + " |", "|---|" + "---|" * len(defects)]
    for m in [k for k in metrics if labels.get(k, ("", ""))[1] == "paper"] + ["gt_f1"]:
        cells = []
        for d in defects:
            r = cell.get((m, d))
            cells.append("-" if r is None else " / ".join(_fmt(a) for a in r["auc_levels"]))
        lines.append(f"| {labels.get(m, (m,))[0]} | " + " | ".join(cells) + " |")
    lines += ["", "Defects each paper metric cannot see (the paired AUC's 95 % interval holds 0.5):", ""]
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
    for k, (what, lo, hi) in enumerate((("auc_paired", 0.0, 1.0), ("spearman", -1.0, 1.0))):
        ax = fig.add_subplot(1, 2, k + 1)
        z = np.array([[float(cell[(m, d)].get(what, np.nan)) if (m, d) in cell else np.nan for d in defects]
                      for m in metrics])
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
        ax.set_title("paired AUC (defective vs its clean)" if what == "auc_paired" else "Spearman rho with 1 - GT F1",
                     fontsize=8)
        fig.colorbar(im, ax=ax, fraction=0.04, pad=0.02).ax.tick_params(labelsize=6)
    if title:
        fig.suptitle(title, fontsize=8)
    with atomic_open(path, "wb") as fh:
        fig.savefig(fh, format="png", dpi=130, bbox_inches="tight")


_CSV = ("set", "metric", "group", "defect", "auc", "auc_lo", "auc_hi", "auc_paired", "auc_paired_lo", "auc_paired_hi",
        "effect", "effect_lo", "effect_hi", "wilcoxon_p", "n_pairs", "spearman", "n_clean", "n_defective", "auc_levels")


def _csv_row(r: dict[str, Any]) -> list[Any]:
    flat = {**r, "auc_lo": r["auc_ci"][0], "auc_hi": r["auc_ci"][1], "auc_paired_lo": r["auc_paired_ci"][0],
            "auc_paired_hi": r["auc_paired_ci"][1], "effect_lo": r["effect_ci"][0], "effect_hi": r["effect_ci"][1],
            "auc_levels": " ".join(_fmt(a, 4) for a in r["auc_levels"])}
    return [flat[k] for k in _CSV]


def write_report(folder: Path, rows: list[dict[str, Any]], *, figure: bool = True,
                 note: str = "") -> list[dict[str, Any]]:
    """Write the four outputs (module docstring) for ``rows``; returns the statistics table (every
    set's records, each with its ``set``)."""
    folder = Path(folder)
    metric_keys = sorted({k for r in rows for k in r} - set(ROW_KEYS))
    _write_text(folder / "scores.csv", _csv_text([*ROW_KEYS, *metric_keys],
                                                 [[r.get(k, "") for k in ROW_KEYS] + [r.get(k) for k in metric_keys]
                                                  for r in rows]))
    tables = set_tables(rows)
    table = [rec for t in tables.values() for rec in t]
    _write_text(folder / "validity.csv", _csv_text(list(_CSV), [_csv_row(r) for r in table]))
    head = ("# Which metric sees which defect\n\n" + (f"{note}. " if note else "") +
            f"{len(rows)} scored skeletons. Intervals: 95 % bootstrap over (shape, seed) clusters; rho = "
            "Spearman correlation with the ground-truth error 1 - F1. docs/validity.md explains all.\n\n")
    body = "".join(f"## {'The benchmark shapes' if name == 'shapes' else 'The traced neurons'}\n\n"
                   + markdown_table(t) + "\n" for name, t in tables.items())
    _write_text(folder / "validity.md", head + body)
    if figure and table:
        first = next(iter(tables))
        draw_heatmap(tables[first], folder / "validity.png", f"{note} ({first})" if note else first)
        for name in list(tables)[1:]:
            draw_heatmap(tables[name], folder / f"validity_{name}.png", f"{note} ({name})" if note else name)
    return table
