"""The Defects panel's rows (app/scene/defects.py, Qt-free) for the defects the main GUI test does not
make: a spurious cycle (a chord bowed inside the torus's tube closes a small loop), a missing cycle
(genus 2 with one loop cut), a collapsed skeleton; and a clean shape's none."""

from __future__ import annotations

import numpy as np
from diagnostics_helpers import attach_path

from skelscope.scene.defects import defect_counts, defect_rows, sound_line
from skelcore import evaluate, shapes
from skelcore.curve import CurveSkeleton


def test_a_chord_inside_the_torus_tube_is_a_spurious_cycle_row_on_its_edges():
    s = shapes.torus(n=4000, n_curve=32, seed=5)
    mid = (s.curve_vertices[0] + s.curve_vertices[3]) / 2 * 1.1  # 0.1 R outward, inside the tube
    v, e, ids = attach_path(s.curve_vertices, s.curve_edges, 0, mid, 2, to=None)
    v, e, _ = attach_path(v, e, int(ids[-1]), s.curve_vertices[3], 1, to=3)
    curve = CurveSkeleton.from_raw(v, e)
    ev = evaluate(s.cloud, curve=curve)
    (row,) = [r for r in defect_rows(ev) if r.code == "spurious_cycles"]
    edges = np.asarray(curve.edges)[row.edges]
    chord = set(ids.tolist())
    assert any(chord & set(pair) for pair in edges.tolist())  # the chord's edges are in it
    assert not np.isin(edges, np.arange(10, 30)).all(axis=1).any()  # the long arc is not
    assert "goes around no tunnel" in row.size and row.bounds() is not None
    assert defect_counts(ev)["spurious_cycles"] == 1 and "spurious_cycles" in sound_line(ev)


def test_genus2_with_one_loop_cut_has_a_missing_cycle_row_without_a_place():
    s = shapes.genus2(n=4000, seed=4)
    ev = evaluate(s.cloud, curve=CurveSkeleton.from_raw(s.curve_vertices, s.curve_edges[3:]))
    (row,) = [r for r in defect_rows(ev) if r.code == "missing_cycles"]
    assert row.size.endswith("1 missing") and row.bounds() is None  # the camera frames the whole scene


def test_a_collapsed_skeleton_is_a_collapse_row_on_the_skeleton():
    s = shapes.cylinder(n=3000, seed=2)
    tiny = np.array([[0, 0, 2.0], [0, 0, 2.01], [0, 0, 2.02]])
    ev = evaluate(s.cloud, curve=CurveSkeleton.from_raw(tiny, [[0, 1], [1, 2]]))
    (row,) = [r for r in defect_rows(ev) if r.code == "collapse"]
    assert row.size == next(w.message for w in ev.warnings if w.code == "collapse")
    np.testing.assert_allclose(row.bounds()[0], tiny.min(axis=0))


def test_a_clean_shape_has_no_row_and_is_sound():
    s = shapes.torus(n=3000, seed=1)
    ev = evaluate(s.cloud, s.skeletal, CurveSkeleton.from_raw(s.curve_vertices, s.curve_edges))
    assert defect_rows(ev) == [] and sound_line(ev) == "sound" and defect_rows(None) == []


def test_the_defects_dock_names_the_checks_that_did_not_run():
    """The Defects dock's status line: a check switched off is named with its reason, never silent."""
    from types import SimpleNamespace

    ev = SimpleNamespace(warnings=[], not_computed={"outside": "the cloud is not a closed surface", "coverage": "x"})
    assert sound_line(ev) == "sound; not checked: outside (the cloud is not a closed surface)"
