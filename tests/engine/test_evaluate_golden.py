"""``evaluate`` gives, bit for bit, the outputs stored in tests/engine/golden/evaluate_golden.json (the
stages change no value): the samples with both skeleton kinds, every correspondence
(pointwise, index, reverse from a set and from a curve alone, none), a reference curve, coverage on and
off, one lane and all, and the real hammer and apple tree (resources/scans) with skeletons by ``skeletonize`` ("cao").

The local values that go through BLAS and LAPACK (curve centeredness' fits, smoothness' principal axes)
change their last bits with the CPU's kernels: where their hash differs, their stored values
(``evaluate_golden_values.npz``) are compared within ``make_golden.MACHINE_ATOL``, and so are the
document's smoothness and centeredness scores; everything else, bit for bit.
"""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import numpy as np
import pytest

GOLDEN_DIR = Path(__file__).resolve().parent / "golden"


def _load_maker():
    spec = importlib.util.spec_from_file_location("make_golden", GOLDEN_DIR / "make_golden.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


make_golden = _load_maker()
STORED = json.loads((GOLDEN_DIR / "evaluate_golden.json").read_text())
VALUES = np.load(make_golden.VALUES)
#: document and scalar paths whose numbers follow the machine-dependent local values
MACHINE_PATHS = ("smoothness", "centeredness")


def _number(v) -> float | None:
    """A JSON number, or a float's repr as the scalars store it; None for anything else."""
    if isinstance(v, bool) or v is None:
        return None
    if isinstance(v, (int, float)):
        return float(v)
    try:
        return float(v) if isinstance(v, str) else None
    except ValueError:
        return None


def _close(where: str, stored, now) -> bool:
    """A document or scalar number of a machine-dependent score within the tolerance."""
    if where.startswith("/arrays/") or not any(p in where for p in MACHINE_PATHS):
        return False
    a, b = _number(stored), _number(now)
    return a is not None and b is not None and abs(a - b) <= make_golden.MACHINE_ATOL


def _machine_tolerated(name: str, differences: list[str], values: dict) -> list[str]:
    """``differences`` less the machine-dependent arrays whose values are the stored ones within the
    tolerance (the same shape and the same NaNs)."""
    out = []
    for d in differences:
        key = d.split(":")[0][len("/arrays/"):] if d.startswith("/arrays/") else None
        if key in make_golden.MACHINE_DEPENDENT and f"{name}/{key}" in VALUES.files and key in values:
            old, now = VALUES[f"{name}/{key}"], values[key]
            if (old.shape == now.shape and np.array_equal(np.isnan(old), np.isnan(now))
                    and np.nanmax(np.abs(old - now), initial=0.0) <= make_golden.MACHINE_ATOL):
                continue
        out.append(d)
    return out


def _differences(stored, now, where: str = "") -> list[str]:
    """Every path at which two JSON-like values differ (floats compared exactly)."""
    if isinstance(stored, dict) and isinstance(now, dict):
        out = [f"{where}/{k}: missing now" for k in stored if k not in now]
        out += [f"{where}/{k}: new" for k in now if k not in stored]
        for k in stored:
            if k in now:
                out += _differences(stored[k], now[k], f"{where}/{k}")
        return out
    if isinstance(stored, list) and isinstance(now, list) and len(stored) == len(now):
        return [d for i, (a, b) in enumerate(zip(stored, now)) for d in _differences(a, b, f"{where}[{i}]")]
    if (stored == now and type(stored) is type(now)) or _close(where, stored, now):
        return []
    return [f"{where}: stored {stored!r}, now {now!r}"]


@pytest.mark.parametrize("name", list(make_golden.CASES))
def test_evaluate_gives_the_stored_outputs_bit_for_bit(name):
    case = make_golden.CASES[name]
    stored = STORED[name]
    kwargs = case["make"]()
    assert make_golden.input_hashes(kwargs) == stored["inputs"], "the inputs changed (the skeletonizer?)"
    values: dict = {}
    now = _without_diagnostics(json.loads(json.dumps(make_golden.record(kwargs, values))))  # the stored file's types
    found = _added_after(_differences({k: v for k, v in stored.items() if k != "inputs"}, now))
    assert _machine_tolerated(name, found, values) == []


#: what may be added without changing a stored value: new Params fields and new document blocks
ADDITIONS = ("/doc/params/", "/doc/diagnostics: new", "/doc/ground_truth: new")
#: the diagnostics' stages and warnings (tests/engine/test_diagnostics*.py check them), and the
#: ground-truth stage (tests/engine/test_ground_truth_stage.py checks it), and the stray-point
#: search, a trust check's work run as a stage of its own (tests/engine/test_scan_outliers.py)
DIAGNOSTIC_STAGES = ("curve defects", "skeletal outside", "skeletal missing parts", "curve missing parts",
                     "ground truth", "stray points")
DIAGNOSTIC_CODES = ("incomplete", "spurious_branches", "spurious_cycles", "missing_cycles", "outside")


def _added_after(differences: list[str]) -> list[str]:
    """Differences less the additions, and less the last progress fraction's rounding (the stages'
    weights sum differently once the diagnostics are among them: 0.9999999999999999 or 1.0)."""
    def rounding(d: str) -> bool:
        if not d.startswith("/progress_last: stored "):
            return False
        a, b = d[len("/progress_last: stored "):].split(", now ")
        return abs(float(a) - float(b)) < 1e-9
    return [d for d in differences if not (d.endswith(": new") and d.startswith(ADDITIONS)) and not rounding(d)]


def _without_diagnostics(rec: dict) -> dict:
    """The record as the paper's stages and the trust checks made it: the diagnostics' stages and
    warnings taken out (they come after, and change no stored value)."""
    rec = dict(rec)
    for key in ("stages", "progress_labels"):
        if isinstance(rec.get(key), list):
            rec[key] = [s for s in rec[key] if s not in DIAGNOSTIC_STAGES]
    if isinstance(rec.get("doc"), dict):
        rec["doc"] = dict(rec["doc"])
        rec["doc"]["warnings"] = [w for w in rec["doc"].get("warnings", []) if w["code"] not in DIAGNOSTIC_CODES]
        if isinstance(rec["doc"].get("not_computed"), dict):  # a diagnostic's "not checked" (part of it)
            rec["doc"]["not_computed"] = {k: v for k, v in rec["doc"]["not_computed"].items()
                                          if k not in DIAGNOSTIC_CODES}
    return rec


def test_a_changed_value_is_seen():
    """The comparison is not vacuous: one bit of one local value, or one key, makes it fail."""
    kwargs = make_golden.CASES["torus_lbc_skeletal_only_w1"]["make"]()
    stored = STORED["torus_lbc_skeletal_only_w1"]
    values: dict = {}
    rec = _without_diagnostics(json.loads(json.dumps(make_golden.record(kwargs, values))))
    name = "torus_lbc_skeletal_only_w1"
    assert _machine_tolerated(name, _added_after(_differences({k: v for k, v in stored.items() if k != "inputs"}, rec)),
                              values) == []
    beta = np.fromiter((1.0, 0.5), float)
    beta[1] = np.nextafter(beta[1], 1.0)  # one ulp
    assert make_golden.array_sha(beta) != make_golden.array_sha(np.array([1.0, 0.5]))
    rec["arrays"]["skeletal.boundedness"] = make_golden.array_sha(beta)
    rec["doc"]["not_computed"]["coverage"] = "why"
    rec["doc"]["boundedness"]["skeletal"] = np.nextafter(stored["doc"]["boundedness"]["skeletal"], 2.0)
    found = _machine_tolerated(name, _added_after(_differences({k: v for k, v in stored.items() if k != "inputs"}, rec)),
                               values)
    assert [d.split(":")[0] for d in found] == ["/arrays/skeletal.boundedness", "/doc/boundedness/skeletal",
                                                "/doc/not_computed/coverage"]


def test_a_machine_dependent_value_moved_beyond_the_tolerance_is_seen():
    """The tolerance is not vacuous: a smoothness value moved by 1e-7, or one NaN more, fails; a move
    of 1e-12 (another CPU's kernels) passes; a score moved by 1e-7 in the document fails."""
    name = "torus_lbc"
    kwargs = make_golden.CASES[name]["make"]()
    values: dict = {}
    rec = _without_diagnostics(json.loads(json.dumps(make_golden.record(kwargs, values))))
    stored = {k: v for k, v in STORED[name].items() if k != "inputs"}
    base = _machine_tolerated(name, _added_after(_differences(stored, rec)), values)
    assert base == []
    for shift, seen in ((1e-12, False), (1e-7, True)):
        moved = dict(values, **{"skeletal.smoothness": values["skeletal.smoothness"] + shift})
        changed = json.loads(json.dumps(rec))
        changed["arrays"]["skeletal.smoothness"] = make_golden.array_sha(moved["skeletal.smoothness"])
        found = _machine_tolerated(name, _added_after(_differences(stored, changed)), moved)
        assert (found != []) is seen, (shift, found)
    nan = values["skeletal.smoothness"].copy()
    nan[np.flatnonzero(np.isfinite(nan))[0]] = np.nan
    changed = json.loads(json.dumps(rec))
    changed["arrays"]["skeletal.smoothness"] = make_golden.array_sha(nan)
    assert _machine_tolerated(name, _added_after(_differences(stored, changed)), dict(values, **{"skeletal.smoothness": nan}))
    changed = json.loads(json.dumps(rec))
    changed["doc"]["smoothness"]["skeletal"] = stored["doc"]["smoothness"]["skeletal"] + 1e-7
    found = _machine_tolerated(name, _added_after(_differences(stored, changed)), values)
    assert [d.split(":")[0] for d in found] == ["/doc/smoothness/skeletal"]
