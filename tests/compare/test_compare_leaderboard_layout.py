"""report.html's leaderboard fits a 1400 px window without a wrapped cell, measured in the
real headless Chromium: a script added to the page records, after layout, how many of the
leaderboard's cells take more than one line and how far right its tables reach. The board holds a
value in every compared column of SCORE_COLUMNS (so a group added to the catalogue is in the test),
four methods under three conditions, defective means (†) and every profile."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import pytest

from skelcore.compare.job_store import Store
from skelcore.compare.leaderboard import COLUMNS, Entry, Leaderboard
from skelcore.compare.leaderboard_html import bands, leaderboard_html
from skelcore.compare.profiles import load_profiles
from skelcore.compare.report import write_report
from skelcore.scores import COLUMN
from headless_chromium import browser

MEASURE = """<script>
window.addEventListener('load', function () {
  var vw = document.documentElement.clientWidth, wrapped = 0, cells = 0, right = 0, bad = [];
  var tables = document.querySelectorAll('table.lb');
  tables.forEach(function (t) {
    right = Math.max(right, t.getBoundingClientRect().right);
    t.querySelectorAll('th,td').forEach(function (c) {
      cells++;
      var r = document.createRange(); r.selectNodeContents(c);
      var tops = {};
      Array.prototype.forEach.call(r.getClientRects(), function (q) { if (q.width > 0) tops[Math.round(q.top)] = 1; });
      if (Object.keys(tops).length > 1) { wrapped++; if (bad.length < 5) bad.push(c.textContent); }
    });
  });
  document.body.setAttribute('data-layout', JSON.stringify({vw: vw, tables: tables.length, cells: cells,
    wrapped: wrapped, right: right, bad: bad}));
});
</script>"""

METHODS = ("skelscope", "cao", "cao_truncated", "cao_collapsed")
CONDITIONS = ("normal", "noise", "sparse")


def _board() -> Leaderboard:
    """Every compared column with a value of its printed width: 4 methods x 3 conditions; the broken
    methods' means marked (†, unranked)."""
    profiles = load_profiles()
    entries = []
    for cond in CONDITIONS:
        for mi, meth in enumerate(METHODS):
            e = Entry(meth, cond, n_jobs=12, n_ok=12, n_sound=12 if mi < 2 else 0)
            for c in COLUMNS:
                big = 12.5 if COLUMN[c].digits <= 1 else 0.2176  # counts and seconds reach two digits
                e.mean[c], e.std[c] = big * (1 + 0.1 * mi), big / 2
                e.tainted[c] = mi >= 2
                e.rank[c] = None if mi >= 2 else mi + 1
            e.profiles = {p.name: (mi, 12) if p.when is None else (0, 0) for p in profiles}
            entries.append(e)
    return Leaderboard(entries, profiles)


def _layout(tmp_path: Path, page: Path, width: int = 1400) -> dict:
    text = page.read_text()
    measured = tmp_path / "measured.html"
    measured.write_text(text.replace("</body>", MEASURE + "</body>"))
    dom = browser(tmp_path, "--dump-dom", f"--window-size={width},900", measured.resolve().as_uri())
    assert dom.returncode == 0, dom.stderr[-500:]
    found = re.search(r"data-layout=\"([^\"]*)\"", dom.stdout)
    assert found, "the measuring script did not run"
    return json.loads(found.group(1).replace("&quot;", '"'))


@pytest.fixture(scope="module")
def page(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("lb")
    board = _board()
    return Path(write_report(out, [], board, Store(out), shapes=[], methods=list(METHODS),
                             conditions=list(CONDITIONS)))


def test_every_compared_column_and_group_is_on_the_page(page):
    text = page.read_text()
    for c in COLUMNS:
        assert f'title="{COLUMN[c].label},' in text, c
    assert text.count("<table class=lb>") >= 2 and "Key: " in text
    assert "†" in text and "class=best" in text


def test_no_leaderboard_cell_wraps_and_it_fits_1400_px_in_chromium(page, tmp_path):
    m = _layout(tmp_path, page)
    assert m["vw"] >= 1350 and m["tables"] >= 2
    assert m["cells"] >= len(COLUMNS) * (len(METHODS) * len(CONDITIONS) + 1)
    assert m["wrapped"] == 0, m["bad"]
    assert m["right"] <= m["vw"], m


def test_the_same_page_measured_at_700_px_shows_the_check_can_fail(page, tmp_path):
    """The measurement sees overflow: the tables laid out for 1400 px stick out of a 700 px window."""
    m = _layout(tmp_path, page, width=700)
    assert m["right"] > m["vw"]


def test_bands_keep_groups_whole_while_they_fit_and_split_only_a_group_too_wide():
    assert bands([[100, 100], [150], [50, 50, 50]], 300) == [[(0, [0, 1])], [(1, [0]), (2, [0, 1, 2])]]
    assert bands([[100, 100], [150], [50, 50, 50]], 400) == [[(0, [0, 1]), (1, [0])], [(2, [0, 1, 2])]]
    got = bands([[200, 200, 200, 200]], 450)
    assert got == [[(0, [0, 1])], [(0, [2, 3])]]
    assert bands([[100], [200, 200, 200], [100]], 450) == [[(0, [0])], [(1, [0, 1])], [(1, [2]), (2, [0])]]


def test_a_board_of_one_group_is_one_table():
    e = Entry("m", "normal", 1, 1, n_sound=1)
    for c in COLUMNS:
        e.mean[c] = e.std[c] = math.nan
        e.tainted[c], e.rank[c] = False, None
    e.mean["d_B"], e.std["d_B"] = 0.01, 0.0
    html = leaderboard_html(Leaderboard([e], ()))
    assert html.count("<table class=lb>") == 1 and "the paper&#x27;s scores" in html
