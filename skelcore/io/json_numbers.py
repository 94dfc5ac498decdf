"""Numbers in SkelScope's JSON files, both ways: NaN is written as null and +-inf as "inf" / "-inf"
(JSON has neither; docs/metrics.md 5.5 keeps NaN = invalid), numpy scalars as plain numbers.

One convention for every JSON document the engine writes: the ``evaluate --json`` document
(:mod:`.evaluation_files`) and compare's per-job records (:mod:`skelcore.compare.job_store`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["json_safe", "json_float"]


def json_safe(obj: Any) -> Any:
    """``obj`` with dicts and lists walked: NaN -> None, inf -> "inf", -inf -> "-inf", numpy scalars
    -> Python numbers (tuples become lists)."""
    if isinstance(obj, dict):
        return {k: json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    if isinstance(obj, (float, np.floating)):
        v = float(obj)
        if math.isnan(v):
            return None
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return v
    if isinstance(obj, np.integer):
        return int(obj)
    return obj


def json_float(v: Any) -> float:
    """A number as :func:`json_safe` wrote it: a number, None (NaN) or "inf" / "-inf"."""
    if v is None:
        return math.nan
    if isinstance(v, str):
        return {"inf": math.inf, "-inf": -math.inf}.get(v, math.nan)
    return float(v)
