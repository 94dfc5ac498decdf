"""``DIR/report.html``: one self-contained page (every image inline as a data URI, no script or
style from the network) with the leaderboard, the profiles, the per-metric distributions across
methods (strip plots), the failed jobs, and per shape and condition the paper's graphic-table row
for each method (:mod:`.render`). A small inline script records in ``body[data-images]`` how many
images decoded, which the test reads back from headless Chromium.
"""

from __future__ import annotations

import base64
import html
import io as _io
import math
import os
import time
from typing import Any

import numpy as np

from ..display.plotter import OffscreenPlotter
from ..display.tight_once import tight_layout_once
from ..io.atomic import atomic_open
from ..scores import COLUMN, column_keys, format_score, paired_columns
from ..colors import REFERENCE_COLOR, hex_color
from ..diagnostics.trust import DEFECT_CODES, unchecked_defects
from .leaderboard import Leaderboard
from .leaderboard_html import LEADERBOARD_CSS, leaderboard_html
from .profiles import Profile
from .render import SIZE, VIEWS, render_job
from .render_defects import DEFECT_VIEW, defect_layers, legend_html, render_defects
from .job_store import Store

__all__ = ["write_report", "distributions_png"]

_CSS = """
body{font-family:DejaVu Sans,Arial,sans-serif;margin:24px;color:#222;background:#fff}
h1{font-size:22px}h2{font-size:18px;margin-top:28px;border-bottom:1px solid #ccc}h3{font-size:15px}
table{border-collapse:collapse;font-size:12px;margin:8px 0}
td,th{border:1px solid #ccc;padding:3px 6px;text-align:left;vertical-align:middle}
th{background:#f0f0f0}td.best{font-weight:bold;background:#eef7ee}
.gt td{text-align:center}.gt img{width:160px;height:160px;display:block}
.note{color:#555;font-size:12px}ul.legend{margin:4px 0;padding:0;list-style:none;font-size:11px;max-width:180px;text-align:left}
.swatch{display:inline-block;width:10px;height:10px;margin-right:4px;border:1px solid #888;vertical-align:middle}.fail{color:#a00}ul.warnings{margin:4px 0;padding-left:16px;font-size:12px;max-width:360px;text-align:left}
"""
_SCRIPT = """
window.addEventListener('load',function(){var im=document.images,ok=0;
for(var i=0;i<im.length;i++){if(im[i].complete&&im[i].naturalWidth>0)ok++;}
document.body.setAttribute('data-images',ok+'/'+im.length);});
"""


def _img(data: bytes, alt: str) -> str:
    return f'<img alt="{html.escape(alt)}" src="data:image/png;base64,{base64.b64encode(data).decode()}">'


def distributions_png(rows: list[dict[str, Any]], methods: list[str], conditions: list[str]) -> bytes | None:
    """Strip plots: one panel per score, methods along x, one dot per job coloured by condition."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    ok = [r for r in rows if r["status"] == "ok"]
    scores = column_keys(group=("paper", "skelscope"), compared=True)  # not the run's facts (warnings, time)
    cols = [c for c in scores if any(np.isfinite(r[c]) for r in ok)]
    if not cols:
        return None
    ncol = 4
    nrow = math.ceil(len(cols) / ncol)
    fig = Figure(figsize=(3.2 * ncol, 2.6 * nrow), dpi=90)
    palette = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f"]
    rng = np.random.default_rng(0)
    for i, c in enumerate(cols):
        ax = fig.add_subplot(nrow, ncol, i + 1)
        for ci, cond in enumerate(conditions):
            for mi, meth in enumerate(methods):
                v = np.array([r[c] for r in ok if r["method"] == meth and r["condition"] == cond], float)
                v = v[np.isfinite(v)]
                if not v.size:
                    continue
                x = mi + (ci - (len(conditions) - 1) / 2) * 0.22 + rng.uniform(-0.05, 0.05, v.size)
                ax.plot(x, v, "o", ms=3.5, alpha=0.8, color=palette[ci % len(palette)],
                        label=cond if mi == 0 or not ax.get_legend_handles_labels()[1].count(cond) else None)
        ax.set_xticks(range(len(methods)), methods, fontsize=7, rotation=20)
        ax.set_title(f"{c} {COLUMN[c].arrow}", fontsize=9)
        ax.tick_params(axis="y", labelsize=7)
        ax.ticklabel_format(axis="y", useOffset=False, style="plain")
        ax.set_xlim(-0.6, len(methods) - 0.4)
        if i == 0:
            handles, labels = ax.get_legend_handles_labels()
            seen = {}
            for h, lab in zip(handles, labels):
                seen.setdefault(lab, h)
            ax.legend(seen.values(), seen.keys(), fontsize=7, loc="best")
    tight_layout_once(fig)
    buf = _io.BytesIO()
    fig.savefig(buf, format="png")
    return buf.getvalue()


def _profiles_html(profiles: tuple[Profile, ...]) -> str:
    items = []
    for p in profiles:
        crit = ", ".join(f"{'/'.join(c.metrics)} {'≤' if c.upper else '≥'} {c.bound:g} (weight {c.weight:g})"
                         for c in p.criteria)
        when = f" — only {p.when} conditions" if p.when else ""
        if p.fail_on:
            crit += f"; fails on the defects {', '.join(p.fail_on)}"
        items.append(f"<li><b>{html.escape(p.name)}</b> ({html.escape(p.title)}{when}): {html.escape(crit)}. "
                     f"<span class=note>{html.escape(p.why)}</span></li>")
    return ("<p class=note>These thresholds and weights are our reading of the paper's discussion (section V-B), "
            "not its numbers; edit a copy of resources/profiles.toml and pass --profiles.</p><ul>" + "".join(items) + "</ul>")


def _scores_line(r: dict[str, Any]) -> str:
    """d_B/d_Wp, then "B s/c C s/c", "S s/c": the paper's scores, skeletal/curve, two to a line."""
    def f(k: str) -> str:
        return format_score(r.get(k, math.nan), COLUMN[k].digits, nan="-")

    items = [f"d_B/d_Wp {f('d_B')}/{f('d_Wp')}"]
    items += [f"{metric[0].upper()} {f(sk.key)}/{f(cv.key)}" for metric, sk, cv in paired_columns("paper")]
    return "<br>".join([items[0]] + [" ".join(items[i:i + 2]) for i in range(1, len(items), 2)])


def _ground_truth_line(r: dict[str, Any]) -> str:
    """The job's ground-truth scores under the paper's, when its shape has a reference."""
    cols = [c for c in column_keys(group="ground truth", compared=True) if np.isfinite(float(r.get(c, math.nan)))]
    if not cols:
        return ""
    items = [f"{COLUMN[c].short} {format_score(r[c], 0 if COLUMN[c].digits == 1 else COLUMN[c].digits)}" for c in cols]
    return "<br><span class=gtline>ground truth: " + html.escape(", ".join(items)) + "</span>"


def _reference_legend(rows: list[dict[str, Any]]) -> str:
    """The legend entry of the reference line in the skeleton pictures, when a job has a reference."""
    if not any(np.isfinite(float(r.get("gt_f1", math.nan))) for r in rows):
        return ""
    rgb = hex_color(REFERENCE_COLOR)
    return (f" <span style='display:inline-block;width:24px;height:2px;background:{rgb};vertical-align:middle'>"
            "</span> thin grey line: the reference (ground-truth) curve, drawn under the skeleton; \"ground truth\" "
            "beside the pictures: its scores (docs/metrics.md 5.3.1).")


def _warnings_html(store: Store, r: dict[str, Any]) -> str:
    """The job's warnings beside its pictures, defects first and in red."""
    doc = (store.get(r["key"]) or {}).get("evaluation") or {}
    warnings = sorted(doc.get("warnings") or [], key=lambda w: w["code"] not in DEFECT_CODES)
    skipped = unchecked_defects(doc.get("not_computed"))
    if not warnings and not skipped:
        return "<br><span class=note>no warning</span>"
    items = "".join(f"<li{' class=fail' if w['code'] in DEFECT_CODES else ''}><b>{html.escape(w['code'])}</b>: "
                    f"{html.escape(w['message'])}</li>" for w in warnings)
    items += "".join(f"<li class=note><b>not checked: {html.escape(code)}</b>: {html.escape(why)}</li>"
                     for code, why in skipped.items())
    return f"<ul class=warnings>{items}</ul>"


def _defects_cell(out_dir: str, store: Store, r: dict[str, Any], arrays: dict[str, np.ndarray], alt: str,
                  plotter: OffscreenPlotter | None = None) -> str:
    """The job's defect picture (only the defects it was warned of, each in its colour) and its legend."""
    doc = (store.get(r["key"]) or {}).get("evaluation") or {}
    layers = defect_layers(arrays, [w["code"] for w in doc.get("warnings") or [] if w["code"] in DEFECT_CODES])
    png = render_defects(out_dir, r["key"], arrays, layers, plotter=plotter)
    return f"<td>{_img(png.read_bytes(), alt)}{legend_html(layers)}</td>"


def _graphic_table(out_dir: str, rows: list[dict[str, Any]], store: Store, shapes: list[str], methods: list[str],
                   conditions: list[str]) -> str:
    """Every job's pictures, the 3D ones drawn on one off-screen plotter for the whole table."""
    with OffscreenPlotter(SIZE) as plotter:
        return _graphic_rows(out_dir, rows, store, shapes, methods, conditions, plotter)


def _graphic_rows(out_dir: str, rows: list[dict[str, Any]], store: Store, shapes: list[str], methods: list[str],
                  conditions: list[str], plotter: OffscreenPlotter) -> str:
    out = []
    for shape in shapes:
        out.append(f"<h3>{html.escape(shape)}</h3><table class=gt><tr><th>condition / method</th>"
                   + "".join(f"<th>{v}</th>" for v in VIEWS) + f"<th>{DEFECT_VIEW}</th><th>scores (skeletal/curve)</th></tr>")
        for cond in conditions:
            for meth in methods:
                mine = [r for r in rows if r["shape"] == shape and r["condition"] == cond and r["method"] == meth]
                if not mine:
                    continue
                r = mine[0]  # the first seed
                head = f"<td>{html.escape(cond)} ({html.escape(str(r.get('label', '')))})<br><b>{html.escape(meth)}</b></td>"
                if r["status"] != "ok":
                    out.append(f"<tr>{head}<td colspan={len(VIEWS) + 2} class=fail>{html.escape(r['status'])}: "
                               f"{html.escape(str(r.get('error', '')))}</td></tr>")
                    continue
                arrays = store.arrays(r["key"])
                pngs = render_job(out_dir, r["key"], arrays, plotter=plotter)
                imgs = "".join(f"<td>{_img(pngs[v].read_bytes(), f'{shape} {cond} {meth} {v}')}</td>" for v in VIEWS)
                imgs += _defects_cell(out_dir, store, r, arrays, f"{shape} {cond} {meth} {DEFECT_VIEW}", plotter)
                out.append(f"<tr>{head}{imgs}<td>{_scores_line(r)}{_ground_truth_line(r)}{_warnings_html(store, r)}</td></tr>")
        out.append("</table>")
    return "".join(out)


def write_report(out_dir: str | os.PathLike, rows: list[dict[str, Any]], board: Leaderboard, store: Store, *,
                 shapes: list[str], methods: list[str], conditions: list[str], title: str = "skelcore compare",
                 meta: dict[str, Any] | None = None, inputs: tuple[str, ...] = ()) -> str:
    """Write ``out_dir/report.html`` and return its path."""
    from ..version import __version__

    out_dir = os.fspath(out_dir)
    n_ok = sum(r["status"] == "ok" for r in rows)
    failed = [r for r in rows if r["status"] != "ok"]
    parts = [f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
             f"<style>{_CSS}{LEADERBOARD_CSS}</style></head><body data-images=''>",
             f"<h1>{html.escape(title)}</h1><p class=note>skelcore {__version__}, "
             f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}; {len(rows)} jobs, {n_ok} ok, {len(failed)} failed"]
    for k, v in (meta or {}).items():
        parts.append(f"; {html.escape(str(k))}: {html.escape(str(v))}")
    parts.append("</p><h2>Leaderboard</h2>" + leaderboard_html(board))
    parts.append("<p class=note>Mean ± standard deviation over shapes and seeds of the finished jobs; (rank) among the "
                 "methods under the same condition, best in bold; ↓ lower is better, ↑ higher is better. "
                 "Profile columns: jobs passing / jobs the profile applies to. sound: finished jobs with no defect "
                 "warning / jobs; † a mean that includes a job with a defect (never ranked, so never shown best).</p>")
    if board.sound is not None:
        parts.append("<h2>Leaderboard over the cases where every method is sound</h2><p class=note>"
                     + "<br>".join(html.escape(line) for line in board.sound.scope_lines()) + "</p>"
                     + (leaderboard_html(board.sound) if board.sound.entries else "<p>No case where every method is sound.</p>")
                     + "<p class=note>The same columns over those cases only: every method is scored on the same "
                     "inputs and none is broken there.</p>")
    parts.append("<h2>Application profiles</h2>" + _profiles_html(board.profiles))
    dist = distributions_png(rows, methods, conditions)
    if dist is not None:
        parts.append("<h2>Distributions</h2>" + _img(dist, "per-metric distributions across methods"))
    if failed:
        parts.append("<h2>Failed jobs</h2><table><tr><th>shape</th><th>method</th><th>condition</th><th>seed</th>"
                     "<th>error</th></tr>")
        for r in failed:
            parts.append("<tr>" + "".join(f"<td>{html.escape(str(r[k]))}</td>" for k in ("shape", "method", "condition", "seed"))
                         + f"<td class=fail>{html.escape(str(r.get('error', '')))}</td></tr>")
        parts.append("</table>")
    parts.append("<h2>Graphic table</h2><p class=note>Per shape and condition, for each method (first seed): the "
                 "skeleton (blue points, red curve) over the cloud, the H0 barcodes of the cloud and the skeleton "
                 "(eps* dashed), the skeleton coloured by boundedness, centeredness and smoothness (viridis 0..1, "
                 "magenta = invalid), and its defects: only those it was warned of, each in a colour of its own "
                 "(legend under the picture) on the skeleton in grey." + _reference_legend(rows) + "</p>")
    parts.append(_graphic_table(out_dir, rows, store, shapes, methods, conditions))
    parts.append(f"<script>{_SCRIPT}</script></body></html>\n")
    path = os.path.join(out_dir, "report.html")
    with atomic_open(path, "w", inputs=inputs) as fh:
        fh.write("".join(parts))
    return path
