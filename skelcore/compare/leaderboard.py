"""The leaderboard: per method and condition, the mean and standard deviation over shapes (and
seeds) of every score of the jobs that finished, with its rank among the methods under that
condition (1 = best, ties as printed share a rank; arrows as in the paper's table: lower is better for d_B, d_Wp, warnings and
time, higher for the rest), and each application profile's pass rate. Markdown, CSV and LaTeX.

A mean that includes a defective job is marked and never ranked, so one defect anywhere leaves a
method unranked. :func:`build_sound_leaderboard` answers the question that remains: the same table
over the cases (shape and seed) where every method is sound, so the methods are ranked on the same
inputs, none of them broken there (docs/compare.md "Defects decide").
"""

from __future__ import annotations

import csv
import io as _io
import math
import os
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..io.atomic import atomic_open
from ..scores import COLUMN, column_keys, format_score
from .profiles import Profile

__all__ = ["Entry", "Leaderboard", "build_leaderboard", "build_sound_leaderboard", "LOWER_IS_BETTER"]

COLUMNS = column_keys(compared=True)
TAINT = "†"  # marks a mean that includes a defective job
LOWER_IS_BETTER = frozenset(c for c in COLUMNS if COLUMN[c].better == "lower")


@dataclass
class Entry:
    method: str
    condition: str
    n_jobs: int
    n_ok: int
    mean: dict[str, float] = field(default_factory=dict)
    std: dict[str, float] = field(default_factory=dict)
    rank: dict[str, int | None] = field(default_factory=dict)
    profiles: dict[str, tuple[int, int]] = field(default_factory=dict)  # name -> (passed, applicable)
    n_sound: int = 0  # finished jobs with no defect warning (skelcore.diagnostics.trust.DEFECT_CODES)
    #: column -> True when its mean includes a job with a defect: marked "†", never ranked (so never best)
    tainted: dict[str, bool] = field(default_factory=dict)


@dataclass
class Leaderboard:
    entries: list[Entry]
    profiles: tuple[Profile, ...]
    #: for a board over the cases where every method is sound (:func:`build_sound_leaderboard`): per
    #: condition, (cases kept, cases) and the methods left out for having no sound job there
    sound_cases: dict[str, tuple[int, int]] | None = None
    never_sound: dict[str, list[str]] = field(default_factory=dict)
    #: on the run's board: the same table over the cases where every method is sound (written beside it)
    sound: Leaderboard | None = None

    def arrow(self, col: str) -> str:
        return COLUMN[col].arrow

    def columns(self) -> list[str]:
        """Score columns that at least one entry has (a run without curves shows no curve column)."""
        return [c for c in COLUMNS if any(not math.isnan(e.mean.get(c, math.nan)) for e in self.entries)]

    # ---- formats ------------------------------------------------------------------------------
    def to_csv(self) -> str:
        buf = _io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        head = ["method", "condition", "n_jobs", "n_ok", "n_sound"]
        for c in COLUMNS:
            head += [f"{c}_mean", f"{c}_std", f"{c}_rank"]
        head += [f"profile_{p.name}" for p in self.profiles]
        w.writerow(head)
        for e in self.entries:
            row: list[Any] = [e.method, e.condition, e.n_jobs, e.n_ok, e.n_sound]
            for c in COLUMNS:
                row += [_num(e.mean[c]), _num(e.std[c]), "" if e.rank[c] is None else e.rank[c]]
            row += [_rate(e.profiles[p.name], digits=None) for p in self.profiles]
            w.writerow(row)
        return buf.getvalue()

    def _cells(self, e: Entry, cols: list[str]) -> list[str]:
        out = []
        for c in cols:
            m, s, r = e.mean[c], e.std[c], e.rank[c]
            if math.isnan(m):
                out.append("-")
                continue
            d = COLUMN[c].digits
            mark = TAINT if e.tainted.get(c) else ""
            out.append(f"{format_score(m, d)}{mark} ± {format_score(s, d)}" + (f" ({r})" if r is not None else ""))
        return out

    def to_markdown(self) -> str:
        cols = self.columns()
        head = ["method", "condition", "ok", "sound"] + [f"{c} {self.arrow(c)}" for c in cols] + [p.name for p in self.profiles]
        rows = [head]
        for e in self.entries:
            rows.append([e.method, e.condition, f"{e.n_ok}/{e.n_jobs}", f"{e.n_sound}/{e.n_jobs}", *self._cells(e, cols),
                         *(_rate(e.profiles[p.name]) for p in self.profiles)])
        widths = [max(len(r[i]) for r in rows) for i in range(len(head))]
        lines = ["| " + " | ".join(c.ljust(w) for c, w in zip(rows[0], widths)) + " |",
                 "|" + "|".join("-" * (w + 2) for w in widths) + "|"]
        lines += ["| " + " | ".join(c.ljust(w) for c, w in zip(r, widths)) + " |" for r in rows[1:]]
        if self.sound_cases is not None:
            return self._sound_markdown(lines)
        notes = ["", "Mean ± standard deviation over shapes and seeds of the jobs that finished; (rank) among the "
                 "methods under the same condition, 1 = best; ↓ lower is better, ↑ higher is better. Profile "
                 "columns: jobs passing / jobs it applies to (thresholds: our reading of the paper, section V-B). "
                 f"sound: finished jobs with no defect warning / jobs; {TAINT} a mean that includes a job with a "
                 "defect (not ranked: a defective skeleton is never shown best)."]
        return "\n".join(lines + notes) + "\n"

    def scope_lines(self) -> list[str]:
        """Per condition, which cases the sound-case board keeps and which methods it leaves out."""
        out = []
        for cond, (kept, n) in (self.sound_cases or {}).items():
            line = f"{cond}: {kept} of {n} cases (shape, seed) where every method is sound"
            if self.never_sound.get(cond):
                line += f"; left out, sound on no case: {', '.join(self.never_sound[cond])}"
            out.append(line)
        return out

    def _sound_markdown(self, table: list[str]) -> str:
        notes = ["", *(f"- {line}" for line in self.scope_lines()), "",
                 "Mean ± standard deviation over those cases only, so every method is scored on the same "
                 "inputs and none is broken there; (rank) among the methods under the same condition, 1 = best."]
        if not self.entries:
            table = ["No case where every method is sound."]
        return "\n".join(table + notes) + "\n"

    def to_latex(self) -> str:
        cols = self.columns()
        esc = _tex_escape
        head = ["Method", "Condition", "Sound"] + [f"{COLUMN[c].tex}${COLUMN[c].tex_arrow}$" for c in cols] + [esc(p.name) for p in self.profiles]
        lines = [r"\begin{tabular}{ll" + "l" * (len(cols) + len(self.profiles)) + "}", r"\hline",
                 " & ".join(head) + r" \\ \hline\hline"]
        for e in self.entries:
            cells = [c.replace("±", r"$\pm$") for c in self._cells(e, cols)]
            cells = [r"\textbf{" + c + "}" if c.endswith("(1)") else c for c in cells]
            cells = [c.replace(TAINT, r"$^\dagger$") for c in cells]
            lines.append(" & ".join([esc(e.method), esc(e.condition), f"{e.n_sound}/{e.n_jobs}", *cells,
                                     *(esc(_rate(e.profiles[p.name])) for p in self.profiles)]) + r" \\")
        lines += [r"\hline", r"\end{tabular}"]
        return "\n".join(lines) + "\n"

    def write(self, out_dir: str | os.PathLike, inputs: tuple[str, ...] = (), stem: str = "leaderboard") -> dict[str, str]:
        paths = {}
        for ext, text in (("md", self.to_markdown()), ("csv", self.to_csv()), ("tex", self.to_latex())):
            path = os.path.join(out_dir, f"{stem}.{ext}")
            with atomic_open(path, "w", inputs=inputs) as fh:
                fh.write(text)
            paths[ext] = path
        if self.sound is not None:
            paths.update({f"sound_{k}": v for k, v in self.sound.write(out_dir, inputs, stem=f"{stem}_sound").items()})
        return paths


def _num(v: float) -> str:
    return "" if math.isnan(v) else repr(float(v))


def _rate(pr: tuple[int, int], digits: int | None = 2) -> str:
    passed, n = pr
    if n == 0:
        return "n/a"
    if digits is None:
        return repr(passed / n)
    return f"{passed}/{n}"


def _tex_escape(text: str) -> str:
    for a, b in (("\\", r"\textbackslash{}"), ("&", r"\&"), ("%", r"\%"), ("_", r"\_"), ("#", r"\#"),
                 ("$", r"\$"), ("{", r"\{"), ("}", r"\}")):
        text = text.replace(a, b) if a != "\\" else text.replace(a, "\x00")
    return text.replace("\x00", r"\textbackslash{}")


def _ranks(values: list[float], lower_better: bool, digits: int) -> list[int | None]:
    """Competition ranks (1, 2, 2, 4) of the finite values as shown (rounded to ``digits``), so two
    methods that print the same mean share a rank; None for NaN."""
    out: list[int | None] = []
    shown = [v if math.isnan(v) else round(v, digits) for v in values]
    finite = [v for v in shown if not math.isnan(v)]
    for v in shown:
        if math.isnan(v):
            out.append(None)
        else:
            out.append(1 + sum(1 for w in finite if (w < v if lower_better else w > v)))
    return out


def build_leaderboard(rows: list[dict[str, Any]], profiles: tuple[Profile, ...],
                      methods: list[str], conditions: list[str]) -> Leaderboard:
    """Aggregate ``results.csv`` rows (see :mod:`.results_csv`) in manifest order of methods and conditions."""
    entries = []
    for cond in conditions:
        group = []
        for meth in methods:
            mine = [r for r in rows if r["method"] == meth and r["condition"] == cond]
            if not mine:
                continue
            ok = [r for r in mine if r["status"] == "ok"]
            e = Entry(meth, cond, len(mine), len(ok))
            e.n_sound = sum(1 for r in ok if not r.get("defects"))
            for c in COLUMNS:
                vals = np.array([r.get(c, math.nan) for r in ok], dtype=float)  # older rows lack newer columns
                e.tainted[c] = any(r.get("defects") and np.isfinite(float(r.get(c, math.nan))) for r in ok)
                vals = vals[np.isfinite(vals)]
                e.mean[c] = float(vals.mean()) if vals.size else math.nan
                e.std[c] = float(vals.std(ddof=1)) if vals.size > 1 else (0.0 if vals.size else math.nan)
            for p in profiles:
                verdicts = [r[f"profile_{p.name}"] for r in mine]
                e.profiles[p.name] = (verdicts.count("pass"), sum(v != "n/a" for v in verdicts))
            group.append(e)
        for c in COLUMNS:
            clean = [math.nan if e.tainted[c] else e.mean[c] for e in group]
            for e, r in zip(group, _ranks(clean, c in LOWER_IS_BETTER, COLUMN[c].digits)):
                e.rank[c] = r if len(group) > 1 and COLUMN[c].better else None  # a fact (length ratio): unranked
        entries += group
    return Leaderboard(entries, profiles)


def build_sound_leaderboard(rows: list[dict[str, Any]], profiles: tuple[Profile, ...],
                            methods: list[str], conditions: list[str]) -> Leaderboard:
    """The leaderboard over the cases where every method is sound: per condition, the (shape, seed)
    cases in which each method's job finished with no defect warning. A method sound on no case of a
    condition is left out of it (named in ``never_sound``), or it would leave no case at all."""
    kept_rows: list[dict[str, Any]] = []
    cases: dict[str, tuple[int, int]] = {}
    never: dict[str, list[str]] = {}
    for cond in conditions:
        mine = [r for r in rows if r["condition"] == cond]
        if not mine:
            continue
        sound = {(r["shape"], r["seed"], r["method"]) for r in mine if r["status"] == "ok" and not r.get("defects")}
        present = [m for m in methods if any(r["method"] == m for r in mine)]
        never[cond] = [m for m in present if not any(key[2] == m for key in sound)]
        ranked = [m for m in present if m not in never[cond]]
        all_cases = list(dict.fromkeys((r["shape"], r["seed"]) for r in mine))
        common = {c for c in all_cases if ranked and all((*c, m) in sound for m in ranked)}
        cases[cond] = (len(common), len(all_cases))
        kept_rows += [r for r in mine if r["method"] in ranked and (r["shape"], r["seed"]) in common]
    board = build_leaderboard(kept_rows, profiles, methods, conditions)
    board.sound_cases, board.never_sound = cases, never
    return board
