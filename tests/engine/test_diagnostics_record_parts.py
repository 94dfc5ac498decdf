"""The diagnostics' record written out key by key when first read (skelcore/diagnostics/record.py): the
same summary as writing it all at once, whichever key is read first, through pickling and copying."""

from __future__ import annotations

import copy
import pickle

import numpy as np

from skelcore import evaluate, shapes
from skelcore.diagnostics.record import Diagnostics
from skelcore.io.json_numbers import json_safe


def _eager(ctx) -> dict:
    """The summary as one json_safe pass over every stage's dictionary (the record's former way)."""
    got = ctx.results
    defects, ms, mc = got.get("curve defects"), got.get("skeletal missing parts"), got.get("curve missing parts")
    d, so = defects.to_dict(), got.get("skeletal outside")
    return json_safe({
        "completeness": {"skeletal": None if ms is None else ms.completeness, "curve": None if mc is None else mc.completeness},
        "missing_parts": {"skeletal": None if ms is None else ms.to_dict(), "curve": None if mc is None else mc.to_dict()},
        "branches": d["branches"], "spurious_branches": d["spurious_branches"], "cycles": d["cycles"],
        "outside": d["outside"], "components": d["components"], "along_surface": d["along_surface"],
        "skeletal_outside": so.to_dict().get("skeletal") if so is not None and so.skeletal_outside is not None else None,
    })


def _y():
    sh = shapes.y_shape(1500, seed=4, n_curve_per_arm=8)
    spur = np.vstack([sh.curve_vertices, sh.curve_vertices[3] + [0.0, 0.0, 0.9]])  # a spur leaving the shape
    edges = np.vstack([sh.curve_edges, [[3, len(spur) - 1]]])
    return evaluate(sh.cloud, sh.skeletal, (spur, edges))


def test_the_summary_read_key_by_key_is_the_whole_summary():
    ev = _y()
    want = _eager(ev.source.ctx)
    assert want["branches"]["n_branches"] > 3 and want["outside"]["length_share"] > 0 and want["skeletal_outside"]
    for first in ("outside", "completeness", "branches"):
        d = _y().diagnostics
        assert d.part(first) == want[first]
        assert d.part("nothing such") is None
        assert list(d.summary) == list(want) and d.summary == want
        assert d.part(first) == want[first] and d.to_dict() is d.summary


def test_a_pickled_or_copied_record_carries_its_whole_summary():
    d = _y().diagnostics
    want = _eager(_y().source.ctx)
    back = pickle.loads(pickle.dumps(d))
    assert back.summary == want and back == d and back.part("completeness") == want["completeness"]
    twin = copy.copy(_y().diagnostics)
    assert twin.summary == want and set(twin.arrays) == set(d.arrays)
    given = Diagnostics(summary={"outside": {"length_share": 0.5}})
    assert given.part("outside") == {"length_share": 0.5} and given.part("completeness") is None
