"""The anchor: gudhi's Vietoris-Rips H0 persistence of the hammer scan (4096 points, no edge-length
limit, the 1-skeleton), the yardstick of the engine's speed targets (docs/performance.md). Every other
case is read as its ratio to this one, timed in the same run (benchmarks/report.py), so that a slower
or busier machine moves both. The file's name sorts first: the anchor is timed before the others."""

from __future__ import annotations

import pytest

#: the report finds the anchor by this extra_info key
ANCHOR = "anchor"


def test_gudhi_rips_h0_hammer(measure, benchmark, hammer):
    gudhi = pytest.importorskip("gudhi")

    def rips_h0():
        st = gudhi.RipsComplex(points=hammer).create_simplex_tree(max_dimension=1)
        return st.persistence()

    benchmark.extra_info[ANCHOR] = True
    benchmark.extra_info["n_points"] = len(hammer)
    pairs = measure(rips_h0, rounds=3, warmup=0)
    assert sum(1 for dim, (_b, d) in pairs if dim == 0 and d == float("inf")) >= 1
