"""``evaluate`` gives, bit for bit, the outputs stored in tests/engine/golden/evaluate_golden.json (the
stages change no value): the samples with both skeleton kinds, every correspondence
(pointwise, index, reverse from a set and from a curve alone, none), a reference curve, coverage on and
off, one lane and all, and the real hammer and apple tree (resources/scans) with skeletons by ``skeletonize`` ("cao").

Stored on this machine's build of the kernels: another CPU or BLAS may change the last bits (then rerun
tests/engine/golden/make_golden.py there and compare the documents, not the hashes).
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
    return [] if stored == now and type(stored) is type(now) else [f"{where}: stored {stored!r}, now {now!r}"]


@pytest.mark.parametrize("name", list(make_golden.CASES))
def test_evaluate_gives_the_stored_outputs_bit_for_bit(name):
    case = make_golden.CASES[name]
    stored = STORED[name]
    kwargs = case["make"]()
    assert make_golden.input_hashes(kwargs) == stored["inputs"], "the inputs changed (the skeletonizer?)"
    now = _without_diagnostics(json.loads(json.dumps(make_golden.record(kwargs))))  # the stored file's types
    assert _added_after(_differences({k: v for k, v in stored.items() if k != "inputs"}, now)) == []


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
    rec = _without_diagnostics(json.loads(json.dumps(make_golden.record(kwargs))))
    assert _added_after(_differences({k: v for k, v in stored.items() if k != "inputs"}, rec)) == []
    beta = np.fromiter((1.0, 0.5), float)
    beta[1] = np.nextafter(beta[1], 1.0)  # one ulp
    assert make_golden.array_sha(beta) != make_golden.array_sha(np.array([1.0, 0.5]))
    rec["arrays"]["skeletal.boundedness"] = make_golden.array_sha(beta)
    rec["doc"]["not_computed"]["coverage"] = "why"
    rec["doc"]["boundedness"]["skeletal"] = np.nextafter(stored["doc"]["boundedness"]["skeletal"], 2.0)
    found = _added_after(_differences({k: v for k, v in stored.items() if k != "inputs"}, rec))
    assert [d.split(":")[0] for d in found] == ["/arrays/skeletal.boundedness", "/doc/boundedness/skeletal",
                                                "/doc/not_computed/coverage"]
