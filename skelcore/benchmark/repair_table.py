"""The repair benchmark's rows (:mod:`.repair_bench`) in words: per tool the mean GT F1 before and after
(and on the held reference, where the cases' facts are known),
the jobs made worse or better by more than :data:`MARGIN`, the defect warnings of each kind before and
after, the repair's seconds against the skeletonization's; and one Markdown table row per job (the
tables of docs/repair.md "Measured")."""

from __future__ import annotations

from collections import Counter
from typing import Any, Sequence

import numpy as np

from .repair_bench import WARNINGS

__all__ = ["MARGIN", "summarize", "summary_lines", "markdown_table"]

#: a job is worse (better) when the repair lowers (raises) its GT F1 by more than this
MARGIN = 0.02


def summarize(rows: Sequence[dict[str, Any]]) -> dict[str, dict[str, Any]]:
    """Per job kind (the tool's name, "defect ..." jobs together as "defects") and "all": counts, means,
    warnings by kind, times."""
    groups: dict[str, list[dict[str, Any]]] = {}
    for r in rows:
        key = "defects" if r["job"].startswith("defect ") else r["job"]
        groups.setdefault(key, []).append(r)
        groups.setdefault("all", []).append(r)
    out = {}
    for key, rs in groups.items():
        ok = [r for r in rs if "f1_after" in r]
        f0 = np.array([r["f1_before"] for r in ok], float)
        f1 = np.array([r["f1_after"] for r in ok], float)
        rep = np.array([r["seconds_repair"] for r in ok], float)
        ratio = [r["seconds_repair"] / r["seconds_skeletonize"] for r in ok if r.get("seconds_skeletonize")]
        out[key] = {
            "jobs": len(rs), "failed": sum("failed" in r for r in rs), "refused": sum("refused" in r for r in rs),
            "repaired": len(ok), "worse": int(np.sum(f1 < f0 - MARGIN)), "better": int(np.sum(f1 > f0 + MARGIN)),
            "f1_before": round(float(f0.mean()), 3) if len(ok) else None,
            "f1_after": round(float(f1.mean()), 3) if len(ok) else None,
            **_held_means([r for r in ok if "held_f1_after" in r]),
            "warnings_before": dict(Counter(w for r in ok for w in r["warnings_before"])),
            "warnings_after": dict(Counter(w for r in ok for w in r["warnings_after"])),
            "seconds_repair_median": round(float(np.median(rep)), 2) if len(ok) else None,
            "seconds_repair_max": round(float(rep.max()), 2) if len(ok) else None,
            "repair_over_skeletonize_median": round(float(np.median(ratio)), 2) if ratio else None,
            "repair_within_skeletonize": sum(x <= 1.0 for x in ratio) if ratio else None, "timed": len(ratio),
        }
    return out


def _held_means(rs: Sequence[dict[str, Any]]) -> dict[str, float]:
    """Mean GT F1 on the held reference before and after (docs/metrics.md 5.3.1), when any row has it."""
    if not rs:
        return {}
    return {f"held_f1_{w}": round(float(np.mean([r[f"held_f1_{w}"] for r in rs])), 3) for w in ("before", "after")}


def _kinds(counts: dict[str, int]) -> str:
    return ", ".join(f"{w} {counts[w]}" for w in WARNINGS if counts.get(w)) or "none"


def summary_lines(rows: Sequence[dict[str, Any]]) -> list[str]:
    """One line per job kind, "all" last."""
    lines = []
    for key, s in sorted(summarize(rows).items(), key=lambda kv: (kv[0] == "all", kv[0])):
        if not s["repaired"]:
            lines.append(f"{key}: jobs {s['jobs']}, failed {s['failed']}, refused {s['refused']}")
            continue
        within = "" if s["repair_within_skeletonize"] is None else \
            f", repair / skeletonization median {s['repair_over_skeletonize_median']} " \
            f"(within it: {s['repair_within_skeletonize']} of {s['timed']})"
        lines.append(f"{key}: jobs {s['jobs']}, failed {s['failed']}, refused {s['refused']}, worse by > {MARGIN} GT F1: "
                     f"{s['worse']}, better by > {MARGIN}: {s['better']}, mean GT F1 {s['f1_before']} -> {s['f1_after']}, "
                     + (f"held {s['held_f1_before']} -> {s['held_f1_after']}, " if "held_f1_before" in s else "")
                     + f"defect warnings {_kinds(s['warnings_before'])} -> {_kinds(s['warnings_after'])}, repair s median "
                     f"{s['seconds_repair_median']} max {s['seconds_repair_max']}{within}")
    return lines


def markdown_table(rows: Sequence[dict[str, Any]]) -> str:
    """The jobs as a Markdown table (docs/repair.md's columns)."""
    head = ["| case | curve | GT F1 before | after | defects before | after | kept | rejected | skeletonize s | "
            "repair s | warnings before | after |", "|" + "---|" * 12]
    body = []
    for r in rows:
        if "f1_after" not in r:
            body.append(f"| {r['case']} | {r['job']} | {r.get('f1_before', '-')} | {r.get('failed') or r.get('refused')} |"
                        + " - |" * 8)
            continue
        sk = "-" if r.get("seconds_skeletonize") is None else r["seconds_skeletonize"]
        body.append(f"| {r['case']} | {r['job']} | {r['f1_before']:.3f} | {r['f1_after']:.3f} | "
                    f"{sum(r['tally_before'].values())} | {sum(r['tally_after'].values())} | {r['kept']} | "
                    f"{r['rejected']} | {sk} | {r['seconds_repair']} | {', '.join(r['warnings_before']) or '-'} | "
                    f"{', '.join(r['warnings_after']) or '-'} |")
    return "\n".join(head + body) + "\n"
