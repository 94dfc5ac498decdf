"""What an Evaluation keeps of its diagnostics: the JSON ``diagnostics`` block and the
per-element arrays (branch ids, defect codes per curve vertex and sample, missing cloud points), as
plain data so that it is saved and read back like the rest of the Evaluation (skelcore.io.evaluation_files)."""

from __future__ import annotations

import threading
from typing import Any, Callable

import numpy as np

from ..io.json_numbers import json_safe
from .defects import CurveDefects
from .missing_parts import MissingParts
from .outside import OutsideDefects

__all__ = ["Diagnostics", "DEFECT_BITS", "diagnostics_record", "defect_names"]

#: one bit per element-level defect code, in the per-element ``*_defects`` arrays
DEFECT_BITS = {"spurious_branches": 1, "spurious_cycles": 2, "outside": 4, "incomplete": 8, "disconnected": 16,
               "along_surface": 32}


class Diagnostics:
    """``summary``: the JSON block (completeness, missing parts, branches, cycles: skeleton / shape /
    spurious / missing, outside length share); ``arrays``: ``curve_vertex_branch``,
    ``curve_sample_branch`` (-1: a junction), ``curve_vertex_defects``, ``curve_sample_defects``,
    ``curve_edge_defects`` (:data:`DEFECT_BITS`), ``skeletal_point_defects`` (the given skeletal set's
    ``outside`` bits), ``cloud_missing_skeletal`` / ``cloud_missing_curve`` (the point's missing
    region, -1: explained or in no counted region).

    The summary of :func:`diagnostics_record` is written out when first read, key by key
    (:meth:`part`): an edit's update whose caller reads two measures (the repair's never-worse rule)
    skips the per-branch lists of a curve of thousands of branches (docs/repair.md "Where the time
    goes"). The results it is made from are not changed after their stage; a pickled or copied record
    carries its whole summary."""

    def __init__(self, summary: dict[str, Any] | None = None, arrays: dict[str, np.ndarray] | None = None, *,
                 parts: dict[str, Callable[[], Any]] | None = None) -> None:
        self._summary = summary
        self.arrays: dict[str, np.ndarray] = {} if arrays is None else arrays
        self._parts = dict(parts or {})
        self._made: dict[str, Any] = {}
        self._lock = threading.Lock()

    @property
    def summary(self) -> dict[str, Any]:
        if self._summary is None:
            self._summary = {key: self.part(key) for key in self._parts}
        return self._summary

    @summary.setter
    def summary(self, value: dict[str, Any]) -> None:
        self._summary, self._parts, self._made = value, {}, {}

    def part(self, key: str) -> Any:
        """``summary[key]`` (None when absent), written out alone when the summary is not yet."""
        if self._summary is not None or key not in self._parts:
            return self.summary.get(key)
        with self._lock:
            if key not in self._made:
                self._made[key] = json_safe(self._parts[key]())
            return self._made[key]

    def to_dict(self) -> dict[str, Any]:
        return self.summary

    def __getstate__(self) -> dict[str, Any]:
        return {"summary": self.summary, "arrays": self.arrays}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__init__(state["summary"], state["arrays"])

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Diagnostics):
            return NotImplemented
        return self.summary == other.summary and self.arrays.keys() == other.arrays.keys() and all(
            np.array_equal(v, other.arrays[k]) for k, v in self.arrays.items())

    def __repr__(self) -> str:
        return f"Diagnostics(summary={self.summary!r}, arrays={self.arrays!r})"


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
    return mp.missing_region()


def diagnostics_record(curve: CurveDefects | None, missing_skeletal: MissingParts | None,
                       missing_curve: MissingParts | None, n_samples: int = 0, *,
                       skeletal_outside: OutsideDefects | None = None) -> Diagnostics:
    """The record from the diagnostics stages' results (any of them may be None: not run)."""
    def nothing() -> None:
        return None

    parts: dict[str, Callable[[], Any]] = {  # the summary's keys in their order, each made when first read
        "completeness": lambda: {"skeletal": None if missing_skeletal is None else missing_skeletal.completeness,
                                 "curve": None if missing_curve is None else missing_curve.completeness},
        "missing_parts": lambda: {"skeletal": None if missing_skeletal is None else missing_skeletal.to_dict(),
                                  "curve": None if missing_curve is None else missing_curve.to_dict()},
        "branches": nothing, "spurious_branches": nothing, "cycles": nothing, "outside": nothing,
        "components": nothing, "along_surface": nothing,
        "skeletal_outside": nothing,
    }
    arrays: dict[str, np.ndarray] = {}
    if curve is not None:
        parts.update(branches=curve.branches.to_dict, spurious_branches=curve.spurs.to_dict,
                     cycles=curve.cycles.to_dict, outside=curve.outside.to_dict,
                     components=curve.components.to_dict, along_surface=curve.surface.to_dict)
        b = curve.branches
        arrays["curve_vertex_branch"] = np.asarray(b.vertex_branch, np.int64)
        arrays["curve_vertex_defects"] = _flags(curve.vertex_flags(), len(b.vertex_branch))
        arrays["curve_edge_defects"] = _flags(curve.edge_flags(), len(b.edge_branch))
        if b.sample_branch is not None:
            arrays["curve_sample_branch"] = np.asarray(b.sample_branch, np.int64)
            arrays["curve_sample_defects"] = _flags(curve.sample_flags(), len(b.sample_branch))
    if skeletal_outside is not None and skeletal_outside.skeletal_outside is not None:
        parts["skeletal_outside"] = lambda: skeletal_outside.to_dict().get("skeletal")
        arrays["skeletal_point_defects"] = _flags({"outside": skeletal_outside.skeletal_outside},
                                                  len(skeletal_outside.skeletal_outside))
    if missing_skeletal is not None:
        arrays["cloud_missing_skeletal"] = _missing_region(missing_skeletal)
    if missing_curve is not None:
        arrays["cloud_missing_curve"] = _missing_region(missing_curve)
    return Diagnostics(arrays=arrays, parts=parts)
