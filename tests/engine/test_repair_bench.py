"""``skelcore bench repair``: the repair measured on a tiny case (the bundled cylinder), the rows, the
table and the summary; a folder that is no benchmark is one line and exit 2."""

from __future__ import annotations

import json

from skelcore.benchmark.repair_table import MARGIN, summarize
from skelcore.cli.main import main


def test_bench_repair_on_the_bundled_cylinder(tmp_path, capsys):
    out = tmp_path / "rows.json"
    assert main(["bench", "repair", "samples", "--out", str(out), "--cases", "cylinder", "--tools", "cao",
                 "--quiet"]) == 0
    rows = json.loads(out.read_text())
    assert [r["job"] for r in rows] == ["cao", "lbc (bundled)"]
    for r in rows:
        assert 0.5 < r["f1_before"] <= 1.0 and r["f1_after"] >= r["f1_before"] - MARGIN
        assert set(r) >= {"tally_before", "tally_after", "warnings_before", "warnings_after", "seconds_repair"}
        assert r["cpu_phases"]["first evaluation"]["n"] == 1  # the repair's CPU by phase
    assert rows[0]["seconds_skeletonize"] > 0 and rows[1]["seconds_skeletonize"] is None
    s = summarize(rows)
    assert s["all"]["jobs"] == 2 and s["all"]["worse"] == 0 and s["cao"]["timed"] == 1
    table = (tmp_path / "rows.md").read_text()
    assert "| cylinder | cao |" in table and "- all: jobs 2" in table
    assert "worse by > 0.02 GT F1: 0" in capsys.readouterr().out


def test_bench_repair_refuses_a_folder_without_a_suite(tmp_path, capsys):
    assert main(["bench", "repair", str(tmp_path), "--out", str(tmp_path / "o.json"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "not a benchmark folder" in err[0] and str(tmp_path) in err[0]
    assert not (tmp_path / "o.json").exists()


def test_bench_repair_refuses_an_unknown_tool(tmp_path, capsys):
    assert main(["bench", "repair", "samples", "--out", str(tmp_path / "o.json"), "--tools", "nope"]) == 2
    assert "unknown tool 'nope'" in capsys.readouterr().err
