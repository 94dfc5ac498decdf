"""The declared stages of an evaluation (skelcore/stages/catalogue.py): each declared once, reading only
context items, waiting for the stage that makes its inputs, selected and started by the rules of
docs/performance.md 6.2 (the kernels first: the curve's boundedness, then the skeletal set's after it)."""

from __future__ import annotations

import pytest

from skelcore import Params, shapes
from skelcore.stages import CATALOGUE
from skelcore.stages.catalogue import select, start_order
from skelcore.stages.context import CONTEXT_ITEMS, build_context


def _ctx(skeletal=True, curve=True, correspondence="auto", every=1, params=Params()):
    sh = shapes.y_shape(600, seed=1)
    return build_context(sh.cloud, sh.skeletal[::every] if skeletal else None,
                         (sh.curve_vertices, sh.curve_edges) if curve else None, params,
                         skeletal_index=None, correspondence=correspondence, reference_curve=None)


def test_every_stage_is_declared_once_with_a_weight_and_known_inputs():
    names = [s.name for s in CATALOGUE]
    assert len(set(names)) == len(names)
    assert all(s.weight > 0 and s.inputs and set(s.inputs) <= set(CONTEXT_ITEMS) for s in CATALOGUE)
    with pytest.raises(KeyError, match="unknown context item"):
        _ctx().made_by("skeleton")


#: the diagnostics start last and wait for the results they read
DIAG = ["curve defects", "skeletal outside", "skeletal missing parts", "curve missing parts"]
DIAG_WAITS = {"curve defects": ("curve boundedness", "curve centeredness"), "skeletal outside": ("skeletal boundedness",),
              "skeletal missing parts": ("skeletal coverage",), "curve missing parts": ("curve coverage",)}


@pytest.mark.parametrize("case, started, waits", [
    (dict(), ["curve boundedness", "skeletal boundedness", "topology", "skeletal centeredness", "skeletal smoothness",
              "curve centeredness", "curve smoothness", "skeletal coverage", "curve coverage", "stray points", *DIAG],
     DIAG_WAITS),
    (dict(correspondence="reverse", every=5),
     ["curve boundedness", "correspondence", "skeletal boundedness", "topology", "skeletal centeredness",
      "skeletal smoothness", "curve centeredness", "curve smoothness", "skeletal coverage", "curve coverage",
      "stray points", *DIAG],
     {"topology": ("correspondence",), "skeletal centeredness": ("correspondence",), **DIAG_WAITS}),
    (dict(skeletal=False, correspondence="reverse"),
     ["curve boundedness", "correspondence", "skeletal boundedness", "curve centeredness", "curve smoothness",
      "topology", "skeletal centeredness", "skeletal smoothness", "curve coverage", "stray points", "curve defects",
      "curve missing parts"],
     {**{s: ("correspondence",) for s in ("topology", "skeletal boundedness", "skeletal centeredness",
                                          "skeletal smoothness")},
      "curve defects": ("curve boundedness", "curve centeredness"), "curve missing parts": ("curve coverage",)}),
    # without coverage the missing parts compute their own (on a subsample above missing_max_points)
    (dict(every=5, params=Params(coverage_max_points=100)),
     ["curve boundedness", "skeletal boundedness", "skeletal smoothness", "curve centeredness", "curve smoothness",
      "stray points", *DIAG], {"curve defects": ("curve boundedness", "curve centeredness"), "skeletal outside": ("skeletal boundedness",)}),
    (dict(skeletal=False), ["curve boundedness", "curve centeredness", "curve smoothness", "curve coverage",
                            "stray points", "curve defects", "curve missing parts"],
     {"curve defects": ("curve boundedness", "curve centeredness"), "curve missing parts": ("curve coverage",)}),
])
def test_stages_are_selected_started_and_wait_by_the_declared_rules(case, started, waits):
    ctx = _ctx(**case)
    order = start_order(select(ctx), ctx)
    assert [s.name for s in order] == started
    assert {s.name: s.after(ctx) for s in order if s.after(ctx)} == waits
    # by schedule only: the skeletal set's kernel starts on the lane that ran the curve's
    assert {s.name: s.waits(ctx)[-1] for s in order if s.waits(ctx) != s.after(ctx)} == (
        {"skeletal boundedness": "curve boundedness"} if any(s.name == "skeletal boundedness" for s in order)
        and case.get("curve", True) else {})
