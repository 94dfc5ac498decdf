"""``repr(evaluation)`` fits a screen: the paper's table as the CLI prints it, the warning codes and
where the data are; ``repr(params)`` names only the fields that differ from the defaults."""

from __future__ import annotations

import pytest

import skelcore
from skelcore import shapes
from skelcore.display.summary_table import format_table
from skelcore.params import Params


@pytest.fixture(scope="module")
def ev():
    sh = shapes.y_shape(600, seed=2)
    return skelcore.evaluate(sh.cloud, sh.skeletal, curve=(sh.curve_vertices, sh.curve_edges),
                             params=Params(beta_star=0.8))


def test_repr_is_the_papers_table_the_warning_codes_and_a_hint(ev):
    text = repr(ev)
    assert len(text) < 2000, len(text)
    assert format_table(ev.scores()) in text  # the CLI's table, scores and counts
    s = ev.scores()
    for value in (s.boundedness_skeletal, s.centeredness_curve, s.smoothness_curve):
        assert f"{value:.3f}" in text
    assert f"(n={s.n_boundedness_curve})" in text
    assert "warnings: " + (", ".join(w.code for w in ev.warnings) or "none") in text
    assert "params: Params(beta_star=0.8)" in text
    assert ".to_frame(kind)" in text and ".summary()" in text
    assert "array(" not in text


def test_repr_lists_warnings_and_what_was_not_computed():
    sh = shapes.y_shape(600, seed=2)
    ev = skelcore.evaluate(sh.cloud, sh.skeletal[:100])
    text = repr(ev)
    assert "no_correspondence" in text and "not computed: topology" in text and len(text) < 2000


def test_params_repr_names_only_the_changed_fields():
    assert repr(Params()) == "Params()"
    p = Params(curve_sampling="invariant", beta_star=0.8, k_center=12)
    assert repr(p) == "Params(beta_star=0.8, k_center=12, curve_sampling='invariant')"
    assert eval(repr(p), {"Params": Params}) == p
