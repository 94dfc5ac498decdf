"""A defect check that does not run says so (docs/diagnostics.md "Checks not run"): on an open scan
the cycle and outside checks are named in ``not_computed`` with their reason, in the CLI's defects
block, the JSON and compare's report."""

from __future__ import annotations

import json

import pytest

from skelcore import shapes
from skelcore.cli import main
from skelcore.compare.report import _warnings_html
from skelcore.io import write_curve_ply, write_points_ply


@pytest.fixture(scope="module")
def half(tmp_path_factory):
    """The front half (y > 0) of a cylinder with its axis: an open surface."""
    d = tmp_path_factory.mktemp("half")
    c = shapes.cylinder(2000)
    write_points_ply(d / "cloud.ply", c.cloud[c.cloud[:, 1] > 0])
    write_curve_ply(d / "curve.ply", c.curve_vertices, c.curve_edges)
    return d


def test_open_surface_names_the_checks_it_switched_off(half, tmp_path, capsys):
    out = tmp_path / "r.json"
    assert main(["evaluate", str(half / "cloud.ply"), "--curve", str(half / "curve.ply"), "--quiet",
                 "--json", str(out)]) == 0
    text = capsys.readouterr()
    assert "open_surface" in text.err
    doc = json.loads(out.read_text())
    skipped = doc["not_computed"]
    assert {"outside", "spurious_cycles", "missing_cycles"} <= set(skipped)
    assert "open_surface" in skipped["outside"] and "boundedness" in skipped["outside"]
    block = text.out[text.out.index("defects:"):]
    for code in ("outside", "spurious_cycles", "missing_cycles"):
        assert f"[not checked: {code}]" in block
    assert "spurious_branches" not in skipped and "incomplete" not in skipped  # those ran
    # the axis lies in no solid voxel of an open half tube, yet it explains it (docs/diagnostics.md "Completeness")
    assert "incomplete" not in {w["code"] for w in doc["warnings"]}
    assert doc["diagnostics"]["completeness"]["curve"] > 0.95
    html = _warnings_html({"k": {"evaluation": doc}}, {"key": "k"})
    assert "not checked: outside" in html and "open_surface" in html
