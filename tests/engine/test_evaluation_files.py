"""An Evaluation saved (the --json document + the npz compare stores) and read back is the same
Evaluation, field by field: every correspondence mode, coverage, a reference curve, NaN
kept, array dtypes and shapes, warnings, not_computed, normalization, params, inputs, timings."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

from skelcore import shapes
from skelcore.errors import SkelInputError
from skelcore import evaluate
from skelcore.evaluation import Evaluation
from skelcore.io.evaluation_files import (evaluation_arrays, evaluation_from_store, load_evaluation,
                                          save_evaluation, to_json_dict)
from skelcore.params import Params


def _differences(a, b, where: str = "ev") -> list[str]:
    """Every place where ``a`` and ``b`` differ, walking dataclass fields, dicts, lists and arrays
    (arrays: same dtype, shape and values, NaN equal to NaN; numbers: NaN equal to NaN). Fields left out
    of equality (``compare=False``: an Evaluation's ``source``, the live state ``update`` re-scores from,
    never written to a file) are left out here too."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        if not (isinstance(a, np.ndarray) and isinstance(b, np.ndarray)):
            return [f"{where}: {type(a).__name__} vs {type(b).__name__}"]
        if a.dtype != b.dtype or a.shape != b.shape:
            return [f"{where}: {a.dtype}{a.shape} vs {b.dtype}{b.shape}"]
        nan_ok = np.issubdtype(a.dtype, np.inexact)
        return [] if np.array_equal(a, b, equal_nan=nan_ok) else [f"{where}: values differ"]
    if isinstance(a, (float, np.floating)) and isinstance(b, (float, np.floating)):
        same = (math.isnan(a) and math.isnan(b)) or a == b
        return [] if same else [f"{where}: {a!r} vs {b!r}"]
    if type(a) is not type(b):
        return [f"{where}: {type(a).__name__} vs {type(b).__name__}"]
    if dataclasses.is_dataclass(a):
        return [d for f in dataclasses.fields(a) if f.compare for d in _differences(getattr(a, f.name), getattr(b, f.name),
                                                                          f"{where}.{f.name}")]
    if isinstance(a, dict):
        if list(a) != list(b):
            return [f"{where}: keys {list(a)} vs {list(b)}"]
        return [d for k in a for d in _differences(a[k], b[k], f"{where}[{k!r}]")]
    if isinstance(a, (list, tuple)):
        if len(a) != len(b):
            return [f"{where}: length {len(a)} vs {len(b)}"]
        return [d for i, (x, y) in enumerate(zip(a, b)) for d in _differences(x, y, f"{where}[{i}]")]
    return [] if a == b else [f"{where}: {a!r} vs {b!r}"]


@pytest.fixture(scope="module")
def evaluations() -> dict[str, Evaluation]:
    sh = shapes.y_shape(1500, seed=3)
    cyl = shapes.cylinder(900, seed=4)
    # a NaN vertex first: the cleaned curve's vertex_map is 1..V, not 0..V-1
    v = np.vstack([[np.nan, np.nan, np.nan], sh.curve_vertices])
    with pytest.warns(UserWarning, match="NaN"):
        curve_nan = evaluate(sh.cloud, sh.skeletal, (v, sh.curve_edges + 1), Params(beta_star=0.6),
                             reference_curve=(sh.curve_vertices * 1.01, sh.curve_edges))
    curve = (sh.curve_vertices, sh.curve_edges)
    reference = (sh.curve_vertices + 0.02, sh.curve_edges)
    rows = np.arange(0, len(sh.cloud), 4)
    return {
        "pointwise": evaluate(sh.cloud, sh.skeletal, curve, reference_curve=reference,
                              inputs={"cloud": "y.ply", "skeletal": "y_skeletal.ply", "curve": None}),
        "pointwise, NaN curve vertex": curve_nan,
        "index": evaluate(sh.cloud, sh.skeletal[rows], curve, skeletal_index=rows, reference_curve=reference,
                          inputs={"cloud": "y.ply", "skeletal_index": "y.idx"}),
        "reverse": evaluate(sh.cloud, sh.skeletal[::9], curve, correspondence="reverse", reference_curve=reference),
        "none": evaluate(sh.cloud, sh.skeletal[::7], curve, reference_curve=reference),
        "curve only, reverse": evaluate(cyl.cloud, None, (cyl.curve_vertices, cyl.curve_edges),
                                        correspondence="reverse",
                                        reference_curve=(cyl.curve_vertices, cyl.curve_edges)),
    }


CASES = ["pointwise", "pointwise, NaN curve vertex", "index", "reverse", "none", "curve only, reverse"]


def test_the_cases_cover_each_mode_coverage_reference_and_nan(evaluations):
    modes = {name: ev.correspondence for name, ev in evaluations.items()}
    assert set(modes.values()) == {"pointwise", "index", "reverse", "none"}
    assert evaluations["curve only, reverse"].skeletal.source == "curve"
    for ev in evaluations.values():
        assert ev.coverage_curve is not None and ev.reference is not None and ev.timings
        assert ev.ground_truth is not None and ev.ground_truth.radius_source == "cloud"
        assert np.isnan(ev.curve.vertex_smoothness).any()  # the junction and the ends
    assert evaluations["none"].warnings and evaluations["none"].not_computed
    assert evaluations["reverse"].skeletal.rows is not None and evaluations["index"].skeletal.index is not None
    assert not np.array_equal(evaluations["pointwise, NaN curve vertex"].curve.curve.vertex_map,
                              np.arange(evaluations["pointwise, NaN curve vertex"].curve.curve.n_vertices))


@pytest.mark.parametrize("case", CASES)
def test_an_evaluation_saved_and_loaded_is_equal_in_every_field(evaluations, case, tmp_path):
    ev = evaluations[case]
    save_evaluation(ev, tmp_path / "ev.npz", tmp_path / "ev.json")
    back = load_evaluation(tmp_path / "ev.npz", tmp_path / "ev.json")
    assert _differences(ev, back) == []
    assert _differences(ev.summary(), back.summary()) == []
    assert _differences(ev.summary(0.5, 0.9), back.summary(0.5, 0.9)) == []
    assert back.to_json_dict() == ev.to_json_dict()
    assert back.cloud_columns().keys() == ev.cloud_columns().keys()


def test_the_comparison_sees_a_changed_field(evaluations, tmp_path):
    ev = evaluations["reverse"]
    save_evaluation(ev, tmp_path / "ev.npz", tmp_path / "ev.json")
    back = load_evaluation(tmp_path / "ev.npz", tmp_path / "ev.json")
    assert _differences(ev, back) == []
    back.skeletal.rows = back.skeletal.rows.astype(np.int32)
    back.timings["total"] += 1e-9
    back.coverage_curve.gap[0] = np.nan
    back.reference = dataclasses.replace(back.reference, junctions=(9, 9))
    assert [d.split(":")[0] for d in _differences(ev, back)] == [
        "ev.skeletal.rows", "ev.timings['total']", "ev.coverage_curve.gap", "ev.reference.junctions[0]",
        "ev.reference.junctions[1]"]


def test_a_store_written_before_the_meta_keys_still_reads(evaluations):
    """Stores from before ``ev_meta`` and ``ev_curve_vertex_map``: inputs from the document's paths,
    timings to the microsecond, the curve's vertex map 0..V-1."""
    ev = evaluations["index"]
    arrays = {k: v for k, v in evaluation_arrays(ev).items() if k not in ("ev_meta", "ev_curve_vertex_map")}
    back = evaluation_from_store(to_json_dict(ev), arrays)
    assert back.inputs == {"cloud": "y.ply", "skeletal": None, "curve": None, "skeletal_index": "y.idx"}
    assert back.timings == pytest.approx(ev.timings, abs=1e-6) and back.timings.keys() == ev.timings.keys()
    assert np.array_equal(back.curve.curve.vertex_map, np.arange(back.curve.curve.n_vertices))
    back.inputs, back.timings = ev.inputs, ev.timings
    back.curve.curve = dataclasses.replace(back.curve.curve, vertex_map=ev.curve.curve.vertex_map)
    assert _differences(ev, back) == []


def test_loading_what_is_not_a_saved_evaluation_names_the_file(evaluations, tmp_path):
    np.savez(tmp_path / "other.npz", cloud=np.zeros((3, 3)))
    (tmp_path / "ev.json").write_text(json.dumps(to_json_dict(evaluations["none"])))
    with pytest.raises(SkelInputError, match="other.npz.*no Evaluation"):
        load_evaluation(tmp_path / "other.npz", tmp_path / "ev.json")
    (tmp_path / "bad.json").write_text("[1, 2")
    with pytest.raises(SkelInputError, match="bad.json"):
        load_evaluation(tmp_path / "other.npz", tmp_path / "bad.json")
