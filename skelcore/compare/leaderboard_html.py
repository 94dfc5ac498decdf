"""report.html's leaderboard, laid out to fit the page (no wrapped cell at 1400 px).

The score columns are shown under a header row of their groups (``ScoreColumn.group``: the paper's,
SkelScope's, the diagnostics', the run's, any added later) and a row of their short names
(``ScoreColumn.short``, the full label, unit and direction in a ``title`` tooltip and in the key under
the tables); cells never wrap. Each column's width is measured from its texts (matplotlib's DejaVu
Sans metrics, the page's first font and the widest of its fallbacks), and whole groups are packed into
as few tables ("bands") as fit ``width_px``, each repeating the method, condition, ok and sound
columns, so adding a group adds a band, never a page wider than the screen. A group wider than a band
by itself is split between bands.
"""

from __future__ import annotations

import html
from functools import lru_cache

from ..scores import COLUMN
from .leaderboard import Leaderboard

__all__ = ["leaderboard_html", "LEADERBOARD_CSS", "GROUP_TITLES", "text_px", "bands"]

#: the table's font size and a cell's horizontal padding + border (CSS below), px
FONT_PX = 11
CELL_PAD_PX = 2 * 4 + 1
#: the widest table: a 1400 px window less the page's margins (2 x 24 px), a scroll bar and slack
WIDTH_PX = 1280
GROUP_TITLES = {"paper": "the paper's scores", "skelscope": "SkelScope's", "reference": "reference",
                "ground truth": "ground truth", "diagnostics": "defects found", "run": "the run",
                "profiles": "profiles: jobs passing / applicable"}
LEADERBOARD_CSS = (
    "table.lb{font-size:11px;margin:6px 0 10px}table.lb td,table.lb th{white-space:nowrap;padding:2px 4px}"
    "table.lb th.grp{text-align:center;background:#e4e8ee}table.lb th[title]{cursor:help}"
    "p.key{font-size:11px;color:#555;max-width:1300px}"
)
_FIXED = ("method", "condition", "ok", "sound")


@lru_cache(maxsize=4096)
def text_px(text: str, bold: bool = False, size: float = FONT_PX) -> float:
    """Width in CSS px of ``text`` in DejaVu Sans at ``size`` px (bold: the best cells)."""
    from matplotlib.font_manager import FontProperties
    from matplotlib.textpath import TextToPath

    prop = FontProperties(family="DejaVu Sans", size=size, weight="bold" if bold else "normal")
    return float(TextToPath().get_text_width_height_descent(text, prop, ismath=False)[0])


def _width(header: str, cells: list[tuple[str, bool]], header_bold: bool = True) -> float:
    return CELL_PAD_PX + max([text_px(header, header_bold)] + [text_px(t, b) for t, b in cells]) + 2


def bands(groups: list[list[float]], budget: float) -> list[list[tuple[int, list[int]]]]:
    """Pack ``groups`` (each its columns' widths, in order) into bands of at most ``budget`` px: whole
    groups while they fit, a group wider than a band by itself split at column boundaries. Returns per
    band (group index, indices of its columns within the group)."""
    out: list[list[tuple[int, list[int]]]] = []
    band: list[tuple[int, list[int]]] = []
    used = 0.0
    for name, widths in enumerate(groups):
        total = sum(widths)
        if band and used + total > budget:
            out.append(band)
            band, used = [], 0.0
        if total <= budget:
            band.append((name, list(range(len(widths)))))
            used += total
            continue
        part: list[int] = []
        for i, w in enumerate(widths):  # a group too wide for one band: as many columns per band as fit
            if part and used + w > budget:
                band.append((name, part))
                out.append(band)
                band, used, part = [], 0.0, []
            part.append(i)
            used += w
        band.append((name, part))
    if band:
        out.append(band)
    return out


def _title(key: str) -> str:
    c = COLUMN[key]
    better = {"lower": "lower is better", "higher": "higher is better"}.get(c.better or "", "not ranked")
    return f"{c.label}, {c.unit}; {better}"


def leaderboard_html(board: Leaderboard, width_px: float = WIDTH_PX) -> str:
    """The leaderboard as one or more tables of grouped columns that fit ``width_px``, and a key."""
    cols = board.columns()
    score_cells = {e_i: dict(zip(cols, board._cells(e, cols))) for e_i, e in enumerate(board.entries)}
    fixed_cells = [[e.method, e.condition, f"{e.n_ok}/{e.n_jobs}", f"{e.n_sound}/{e.n_jobs}"] for e in board.entries]
    fixed_w = sum(_width(h, [(row[i], False) for row in fixed_cells]) for i, h in enumerate(_FIXED))

    # groups in catalogue order, then the profiles
    groups: list[tuple[str, list[str]]] = []
    for c in cols:
        g = COLUMN[c].group
        if not groups or groups[-1][0] != g:
            groups.append((g, []))
        groups[-1][1].append(c)
    # per group: its title and per column (header, tooltip, [(cell text, best)])
    items: list[tuple[str, list[tuple[str, str, list[tuple[str, bool]]]]]] = []
    for g, keys in groups:
        items.append((g, [(f"{COLUMN[c].short} {board.arrow(c)}".strip(), _title(c),
                           [(score_cells[i][c], e.rank.get(c) == 1) for i, e in enumerate(board.entries)])
                          for c in keys]))
    if board.profiles:
        items.append(("profiles", [
            (p.name, f"{p.title}: jobs passing / jobs it applies to",
             [("n/a" if e.profiles[p.name][1] == 0 else f"{e.profiles[p.name][0]}/{e.profiles[p.name][1]}", False)
              for e in board.entries]) for p in board.profiles]))
    widths = [[_width(head, cells) for head, _t, cells in cs] for _g, cs in items]
    budget = max(width_px - fixed_w, max((max(w) for w in widths if w), default=0.0))

    out = []
    for band in bands(widths, budget):
        head1 = "".join(f"<th rowspan=2>{h}</th>" for h in _FIXED)
        head1 += "".join(f"<th class=grp colspan={len(idx)}>{html.escape(GROUP_TITLES.get(items[g][0], items[g][0]))}</th>"
                         for g, idx in band)
        head2 = "".join(f"<th title=\"{html.escape(items[g][1][i][1])}\">{html.escape(items[g][1][i][0])}</th>"
                        for g, idx in band for i in idx)
        rows = []
        for ei, e in enumerate(board.entries):
            f = fixed_cells[ei]
            cells = (f"<td>{html.escape(f[0])}</td><td>{html.escape(f[1])}</td><td>{f[2]}</td>"
                     f"<td{' class=fail' if e.n_sound < e.n_jobs else ''}>{f[3]}</td>")
            for g, idx in band:
                for i in idx:
                    text, best = items[g][1][i][2][ei]
                    cells += f"<td{' class=best' if best else ''}>{html.escape(text)}</td>"
            rows.append(f"<tr>{cells}</tr>")
        out.append(f"<table class=lb><tr>{head1}</tr><tr>{head2}</tr>{''.join(rows)}</table>")
    key = "; ".join(f"<b>{html.escape(f'{COLUMN[c].short} {board.arrow(c)}'.strip())}</b> {html.escape(_title(c))}"
                    for c in cols)
    out.append(f"<p class=key>Key: {key}.</p>")
    return "".join(out)
