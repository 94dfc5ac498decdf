"""Counts, precision and recall with Wilson 95 % intervals (``scipy.stats.binomtest``) per warning
code, suite, density and scan condition; written as ``rows.csv`` (every evaluated skeleton),
``calibration.csv`` (the counts) and ``calibration.md`` (the tables docs/diagnostics.md pastes
between its markers: :func:`fill_docs`)."""

from __future__ import annotations

import csv
import io
import os
from pathlib import Path
from typing import Any, Iterable

from scipy.stats import binomtest

from .grid import CODES, CONDITIONS

__all__ = ["DOC_MARKS", "TUNED_ON", "TUNING_NEURONS", "REAL_TUNING", "group_of", "outcome", "summary_rows", "markdown", "write_report", "fill_docs"]

#: the lines between which docs/diagnostics.md holds the generated tables
DOC_MARKS = ("<!-- calibration tables: written by skelcore bench calibrate --docs -->",
             "<!-- end of the calibration tables -->")

#: the traced neurons some codes' thresholds were chosen on; the other neurons are held out and their
#: rows are reported apart from these (docs/diagnostics.md "Precision and recall per warning")
TUNING_NEURONS = ("1734350788", "1734350908")

#: the real suite's label for the tuning neurons' rows
REAL_TUNING = "real, tuning neurons"

#: which data chose each code's thresholds (Params): every other row is held out
TUNED_ON = {c: "synthetic" for c in CODES}
TUNED_ON.update({c: "synthetic + tuning neurons" for c in
                 ("spurious_branches", "missing_cycles", "outside", "outliers", "open_surface")})
TUNED_ON["disconnected"] = "tuning neurons (components_link)"
TUNED_ON.update(trivial_smoothness="none (a fact of the curve)", no_correspondence="none (a fact of the inputs)")


def group_of(row: dict[str, Any]) -> str:
    """The row's table group: its suite, the real suite split into its held-out and tuning neurons."""
    suite = str(row["suite"])
    if suite.startswith("real"):
        return REAL_TUNING if str(row.get("shape", "")) in TUNING_NEURONS else f"{suite}, held-out neurons"
    return suite


def outcome(row: dict[str, Any], code: str) -> str | None:
    """"tp", "fn", "fp", "tn" or None (truth left out); a spur warning counts as a hit only when
    every injected spur is among the flagged branches, a disconnected one only when it flags a piece
    the cut made."""
    truth = row.get(f"truth_{code}")
    if truth is None:
        return None
    fired = bool(row.get(f"fired_{code}"))
    if truth:
        if fired and code == "spurious_branches" and row.get("spurs_located") is False:
            return "fn"
        if fired and code == "disconnected" and row.get("pieces_located") is False:
            return "fn"
        return "tp" if fired else "fn"
    return "fp" if fired else "tn"


def _tuned_here(code: str, group: str) -> bool:
    """Whether ``code``'s thresholds were chosen on the rows of ``group``."""
    tuned = TUNED_ON[code]
    if group == REAL_TUNING:
        return "tuning neurons" in tuned
    return group.startswith("synthetic") and tuned.startswith("synthetic")


def _ci(k: int, n: int) -> tuple[float | None, float | None, float | None]:
    if n == 0:
        return None, None, None
    lo, hi = binomtest(k, n).proportion_ci(confidence_level=0.95, method="wilson")
    return k / n, float(lo), float(hi)


def _counts(rows: Iterable[dict[str, Any]], code: str) -> dict[str, int]:
    c = {"tp": 0, "fn": 0, "fp": 0, "tn": 0}
    for row in rows:
        o = outcome(row, code)
        if o is not None:
            c[o] += 1
    return c


def summary_rows(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """One record per (code, suite, size, condition or "all"): counts, precision, recall and the
    false-alarm rate, each with its Wilson interval."""
    out = []
    groups = sorted({(group_of(r), int(r["size"])) for r in rows},
                    key=lambda g: (g[0] != "synthetic", g[0] == REAL_TUNING, g[1]))
    for code in CODES:
        for suite, size in groups:
            mine = [r for r in rows if group_of(r) == suite and int(r["size"]) == size]
            for cond in ("all", *CONDITIONS):
                sel = mine if cond == "all" else [r for r in mine if r["condition"] == cond]
                if not sel:
                    continue
                c = _counts(sel, code)
                p, plo, phi = _ci(c["tp"], c["tp"] + c["fp"])
                rc, rlo, rhi = _ci(c["tp"], c["tp"] + c["fn"])
                fa, falo, fahi = _ci(c["fp"], c["fp"] + c["tn"])
                out.append({"code": code, "suite": suite, "size": size, "condition": cond, **c,
                            "precision": p, "precision_lo": plo, "precision_hi": phi,
                            "recall": rc, "recall_lo": rlo, "recall_hi": rhi,
                            "false_alarm": fa, "false_alarm_lo": falo, "false_alarm_hi": fahi,
                            "tuned_on": TUNED_ON[code], "held_out": not _tuned_here(code, suite)})
    return out


def _fmt(x: float | None, lo: float | None, hi: float | None) -> str:
    return "-" if x is None else f"{x:.2f} [{lo:.2f}, {hi:.2f}]"


def _size(suite: str, size: int) -> str:
    return f"{suite} {size // 1000}k" if size % 1000 == 0 else f"{suite} {size}"


def markdown(summary: list[dict[str, Any]], *, command: str = "", machine: str = "", wall: float = 0.0,
             rows: list[dict[str, Any]] | None = None) -> str:
    """The tables: per code and density (conditions pooled), then hits / positives and false alarms /
    negatives per scan condition; ``wall`` (s) is named when tasks ran, the evaluations' seconds always."""
    lines = []
    if command:
        rows = rows or []
        evals = sum(float(r.get("seconds") or 0.0) for r in rows)
        lines.append(f"Run: `{command}`" + (f"; {machine}" if machine else "") +
                     (f"; {wall / 60:.1f} min wall" if wall >= 60 else "") +
                     f"; {len(rows)} evaluated skeletons, {evals / 60:.1f} min of evaluation summed over the workers.")
        lines.append("")
    lines += ["Precision = TP / (TP + FP), recall = TP / (TP + FN), false alarms = FP / (FP + TN), each with its "
              "Wilson 95 % interval; `-`: no case to count. Thresholds (`skelcore.Params`) were tuned on the data "
              "named in the column \"tuned on\" (the tuning neurons: " + ", ".join(TUNING_NEURONS) + "); the last "
              "column says whether a row is held out or is that tuning data.", "",
              "| code | suite, density | TP | FN | FP | TN | precision | recall | false alarms | tuned on | these rows |",
              "|---|---|---|---|---|---|---|---|---|---|---|"]
    for s in (x for x in summary if x["condition"] == "all"):
        lines.append(f"| `{s['code']}` | {_size(s['suite'], s['size'])} | {s['tp']} | {s['fn']} | {s['fp']} | {s['tn']} | "
                     f"{_fmt(s['precision'], s['precision_lo'], s['precision_hi'])} | "
                     f"{_fmt(s['recall'], s['recall_lo'], s['recall_hi'])} | "
                     f"{_fmt(s['false_alarm'], s['false_alarm_lo'], s['false_alarm_hi'])} | {s['tuned_on']} | "
                     f"{'held out' if s['held_out'] else 'tuning data'} |")
    conds = list(CONDITIONS)
    lines += ["", "Per scan condition: hits / positives, false alarms / negatives (`-`: none to count).", "",
              "| code | suite, density | " + " | ".join(conds) + " |", "|---|---|" + "---|" * len(conds)]
    by = {(s["code"], s["suite"], s["size"], s["condition"]): s for s in summary}
    for code in CODES:
        for suite, size in sorted({(s["suite"], s["size"]) for s in summary},
                                  key=lambda g: (g[0] != "synthetic", g[0] == REAL_TUNING, g[1])):
            cells = []
            for c in conds:
                s = by.get((code, suite, size, c))
                if s is None:
                    cells.append("")
                    continue
                pos, neg = s["tp"] + s["fn"], s["fp"] + s["tn"]
                cells.append(f"{s['tp']}/{pos if pos else '-'}, {s['fp']}/{neg if neg else '-'}")
            lines.append(f"| `{code}` | {_size(suite, size)} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def _csv_text(records: list[dict[str, Any]]) -> str:
    buf = io.StringIO()
    keys: list[str] = []
    for r in records:
        keys += [k for k in r if k not in keys]
    w = csv.DictWriter(buf, fieldnames=keys, lineterminator="\n")
    w.writeheader()
    for r in records:
        w.writerow({k: ("" if r.get(k) is None else r.get(k)) for k in keys})
    return buf.getvalue()


def write_report(folder: str | os.PathLike, rows: list[dict[str, Any]], *, command: str = "", machine: str = "",
                 wall: float = 0.0) -> list[dict[str, Any]]:
    """``rows.csv``, ``calibration.csv`` and ``calibration.md`` into ``folder`` (atomically)."""
    from ...io.atomic import atomic_open

    folder = Path(folder)
    summary = summary_rows(rows)
    for name, text in (("rows.csv", _csv_text(rows)), ("calibration.csv", _csv_text(summary)),
                       ("calibration.md", markdown(summary, command=command, machine=machine, wall=wall,
                                                   rows=rows))):
        with atomic_open(folder / name, "w") as fh:
            fh.write(text)
    return summary


def fill_docs(path: str | os.PathLike, table: str) -> None:
    """Replace the lines between the two :data:`DOC_MARKS` of ``path`` with ``table`` (atomically);
    a one-line SkelInputError when the markers are missing."""
    from ...errors import SkelInputError
    from ...io.atomic import atomic_open

    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise SkelInputError(f"cannot read the page for the tables: {exc.strerror if isinstance(exc, OSError) else exc}",
                             p) from None
    start, end = text.find(DOC_MARKS[0]), text.find(DOC_MARKS[1])
    if start < 0 or end < start:
        raise SkelInputError("the calibration markers are missing (two lines: " + " / ".join(DOC_MARKS) + ")", p)
    head = text[:start + len(DOC_MARKS[0])]
    with atomic_open(p, "w") as fh:
        fh.write(f"{head}\n\n{table}\n{text[end:]}")
