"""The paper's summary table of an evaluation (docs/metrics.md 5.5: rows d_B / d_Wp, boundedness, centeredness,
smoothness; columns skeletal points / curve skeleton, each score with its count) and the "defects"
block under it, as text (the CLI's ``evaluate``) and as HTML (``Evaluation._repr_html_``,
``show_ab`` in a notebook). The rows come from :func:`skelcore.scores.paper_table`, the numbers from
:class:`skelcore.scores.Scores`: one source for every table.
"""

from __future__ import annotations

import html
from typing import Any, Sequence

from ..scores import Scores, paper_table
from ..diagnostics.trust import DEFECT_CODES, unchecked_defects

__all__ = ["HEADER", "format_table", "table_notes", "format_defects", "summary_html", "tables_html"]

HEADER = ("metric", "skeletal points", "curve skeleton")


def _scores(scores: Scores | dict) -> Scores:
    return scores if isinstance(scores, Scores) else Scores.from_json_dict(scores)


def table_notes(scores: Scores | dict) -> list[str]:
    """The lines under the table: eps* and K (docs/metrics.md 1), what the rows marked "*" are (docs/metrics.md 5.2)."""
    s = _scores(scores)
    notes = []
    if s.d_B is not None:
        notes.append(f"(eps* = {s.text('eps_star')}, K = {s.n_bars} bars compared)")
    if s.coverage_skeletal is not None or s.coverage_curve is not None:
        notes.append(f"(* SkelScope's own, not the paper's: covered fraction of the cloud (slack s = "
                     f"{s.coverage_slack:g}, tau = {s.text('coverage_tau')}), mean / max gap, normalized units)")
    return notes


def format_table(scores: Scores | dict) -> str:
    """The paper's results layout: rows d_B/d_Wp, boundedness, centeredness, smoothness;
    columns skeletal points / curve skeleton, each score with the number of elements it counted
    (a :class:`Scores`, or a ``summary()`` / ``--json`` dict)."""
    s = _scores(scores)
    rows = [HEADER, *paper_table(s, every_row=False)]
    widths = [max(len(r[i]) for r in rows) for i in range(3)]
    lines = []
    for k, r in enumerate(rows):
        lines.append("  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip())
        if k == 0:
            lines.append("  ".join("-" * w for w in widths))
    return "\n".join(lines + table_notes(s))


def _defects(warnings: Sequence[dict]) -> list[dict]:
    return [w for w in warnings if w["code"] in DEFECT_CODES]


def format_defects(warnings: Sequence[dict], not_computed: dict[str, str] | None = None) -> str:
    """The "defects" block under the paper's table: one line per defect warning
    (:data:`skelcore.diagnostics.trust.DEFECT_CODES`), "none found" otherwise; then one line per
    defect check that did not run, with why (``not_computed``; docs/diagnostics.md "Checks not run")."""
    found = _defects(warnings)
    skipped = [f"  [not checked: {code}] {why}" for code, why in unchecked_defects(not_computed).items()]
    if not found:
        return "\n".join(["defects: none found" + (" among the checks run" if skipped else "")] + skipped)
    return "\n".join(["defects:"] + [f"  [{w['code']}] {w['message']}" for w in found] + skipped)


_STYLE = ("<style>.skelscope-table td,.skelscope-table th{padding:2px 10px;text-align:left}"
          ".skelscope-table caption{text-align:left;font-weight:bold}"
          ".skelscope-notes{font-size:85%;margin:2px 0}</style>")


def _esc(text: Any) -> str:
    return html.escape(str(text), quote=True)


def summary_html(ev: Any, title: str | None = None) -> str:
    """The paper's table of ``ev`` as an HTML fragment, then its notes, the defects block and the
    other trust warnings (``Evaluation._repr_html_``)."""
    s = ev.scores()
    caption = title or _caption(ev)
    rows = paper_table(s, every_row=False)
    out = [_STYLE, '<div class="skelscope-evaluation">', f'<table class="skelscope-table"><caption>{_esc(caption)}</caption>',
           "<thead><tr>" + "".join(f"<th>{_esc(h)}</th>" for h in HEADER) + "</tr></thead><tbody>"]
    out += ["<tr>" + "".join(f"<td>{_esc(c)}</td>" for c in row) + "</tr>" for row in rows]
    out.append("</tbody></table>")
    out += [f'<p class="skelscope-notes">{_esc(n)}</p>' for n in table_notes(s)]
    warnings = ev.warning_dicts()
    found = _defects(warnings)
    if not found:
        out.append('<p class="skelscope-defects"><b>defects:</b> none found</p>')
    else:
        out.append('<p class="skelscope-defects"><b>defects:</b></p><ul class="skelscope-defects">')
        out += [f"<li>[{_esc(w['code'])}] {_esc(w['message'])}</li>" for w in found]
        out.append("</ul>")
    skipped = unchecked_defects(getattr(ev, "not_computed", None))
    if skipped:
        out.append('<ul class="skelscope-defects">')
        out += [f"<li>[not checked: {_esc(code)}] {_esc(why)}</li>" for code, why in skipped.items()]
        out.append("</ul>")
    others = [w for w in warnings if w not in found]
    if others:
        out.append('<p class="skelscope-warnings"><b>warnings:</b></p><ul class="skelscope-warnings">')
        out += [f"<li>[{_esc(w['code'])}] {_esc(w['message'])}</li>" for w in others]
        out.append("</ul>")
    out.append("</div>")
    return "\n".join(out)


def tables_html(evaluations: Sequence[Any], titles: Sequence[str]) -> str:
    """Several :func:`summary_html` tables side by side (``show_ab``)."""
    cells = "".join(f'<td style="vertical-align:top;padding-right:24px">{summary_html(ev, t)}</td>'
                    for ev, t in zip(evaluations, titles))
    return f"<table><tr>{cells}</tr></table>"


def _caption(ev: Any) -> str:
    parts = [f"cloud {len(ev.cloud)} points"]
    if ev.skeletal is not None:
        parts.append(f"skeletal set {len(ev.skeletal.points)} points")
    if ev.curve is not None:
        c = ev.curve.curve
        parts.append(f"curve {len(c.vertices)} vertices, {len(c.edges)} edges")
    return "SkelScope evaluation: " + ", ".join(parts)
