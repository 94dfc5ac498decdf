"""What an Evaluation keeps of its diagnostics: the JSON ``diagnostics`` block and the
per-element arrays (branch ids, defect codes per curve vertex and sample, missing cloud points), as
plain data so that it is saved and read back like the rest of the Evaluation (skelcore.io.evaluation_files)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..io.json_numbers import json_safe
from .defects import CurveDefects
from .missing_parts import MissingParts
from .outside import OutsideDefects

__all__ = ["Diagnostics", "DEFECT_BITS", "diagnostics_record", "defect_names"]

#: one bit per element-level defect code, in the per-element ``*_defects`` arrays
DEFECT_BITS = {"spurious_branches": 1, "spurious_cycles": 2, "outside": 4, "incomplete": 8}


@dataclass
class Diagnostics:
    """``summary``: the JSON block (completeness, missing parts, branches, cycles: skeleton / shape /
    spurious / missing, outside length share); ``arrays``: ``curve_vertex_branch``,
    ``curve_sample_branch`` (-1: a junction), ``curve_vertex_defects``, ``curve_sample_defects``,
    ``curve_edge_defects`` (:data:`DEFECT_BITS`), ``skeletal_point_defects`` (the given skeletal set's
    ``outside`` bits), ``cloud_missing_skeletal`` / ``cloud_missing_curve`` (the point's missing
    region, -1: explained or in no counted region)."""

    summary: dict[str, Any]
    arrays: dict[str, np.ndarray] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return self.summary


def defect_names(bits: np.ndarray) -> list[str]:
    """";"-joined defect codes per element of a ``*_defects`` array (the per-point CSVs' cells)."""
    bits = np.asarray(bits, dtype=np.int64)
    out = [""] * len(bits)
    for i in np.flatnonzero(bits):
        out[i] = ";".join(code for code, b in DEFECT_BITS.items() if bits[i] & b)
    return out


def _flags(named: dict[str, np.ndarray | None], n: int) -> np.ndarray:
    out = np.zeros(n, dtype=np.int64)
    for code, flag in named.items():
        if flag is not None and len(flag) == n:
            out[np.asarray(flag, bool)] |= DEFECT_BITS[code]
    return out


def _missing_region(mp: MissingParts) -> np.ndarray:
    return np.where(mp.missing, mp.region, -1).astype(np.int64)


def diagnostics_record(curve: CurveDefects | None, missing_skeletal: MissingParts | None,
                       missing_curve: MissingParts | None, n_samples: int = 0, *,
                       skeletal_outside: OutsideDefects | None = None) -> Diagnostics:
    """The record from the diagnostics stages' results (any of them may be None: not run)."""
    summary: dict[str, Any] = {
        "completeness": {"skeletal": None if missing_skeletal is None else missing_skeletal.completeness,
                         "curve": None if missing_curve is None else missing_curve.completeness},
        "missing_parts": {"skeletal": None if missing_skeletal is None else missing_skeletal.to_dict(),
                          "curve": None if missing_curve is None else missing_curve.to_dict()},
        "branches": None, "spurious_branches": None, "cycles": None, "outside": None,
        "skeletal_outside": None,
    }
    arrays: dict[str, np.ndarray] = {}
    if curve is not None:
        d = curve.to_dict()
        summary.update(branches=d["branches"], spurious_branches=d["spurious_branches"], cycles=d["cycles"],
                       outside=d["outside"])
        b = curve.branches
        arrays["curve_vertex_branch"] = np.asarray(b.vertex_branch, np.int64)
        arrays["curve_vertex_defects"] = _flags(curve.vertex_flags(), len(b.vertex_branch))
        arrays["curve_edge_defects"] = _flags(curve.edge_flags(), len(b.edge_branch))
        if b.sample_branch is not None:
            arrays["curve_sample_branch"] = np.asarray(b.sample_branch, np.int64)
            arrays["curve_sample_defects"] = _flags(curve.sample_flags(), len(b.sample_branch))
    if skeletal_outside is not None and skeletal_outside.skeletal_outside is not None:
        summary["skeletal_outside"] = skeletal_outside.to_dict().get("skeletal")
        arrays["skeletal_point_defects"] = _flags({"outside": skeletal_outside.skeletal_outside},
                                                  len(skeletal_outside.skeletal_outside))
    if missing_skeletal is not None:
        arrays["cloud_missing_skeletal"] = _missing_region(missing_skeletal)
    if missing_curve is not None:
        arrays["cloud_missing_curve"] = _missing_region(missing_curve)
    return Diagnostics(summary=json_safe(summary), arrays=arrays)
