"""``results.csv``: one row per job of the manifest (in manifest order) from the store, with each
application profile's verdict and reason, and the job's warning codes by name (``warnings``), those
that are defects (``defects``, :data:`skelcore.diagnostics.trust.DEFECT_CODES`) and ``sound`` (1: no defect). Empty cells are missing scores, so pandas reads the
file as it is (``pd.read_csv``: NaN there, floats at full precision elsewhere).
"""

from __future__ import annotations

import csv
import io as _io
import math
import os
from typing import Any

from ..io.atomic import atomic_open
from ..io.schemas import SCHEMA_VERSION
from ..scores import column_keys
from ..diagnostics.trust import defect_codes
from .jobs import SCORE_COLUMNS, Job
from .profiles import Profile
from .job_store import Store, json_float

__all__ = ["collect_rows", "write_results_csv", "COLUMNS"]

COLUMNS = ("shape", "method", "condition", "seed", "status", "error", *column_keys(compared=True), "sound",
           "defects", "warnings", "label", "n_points", "key")


def collect_rows(jobs: list[Job], store: Store, profiles: tuple[Profile, ...]) -> list[dict[str, Any]]:
    """A flat row per job; jobs not in the store (a run stopped early) get status "missing"."""
    rows = []
    for job in jobs:
        rec = store.get(job.key) or {}
        scores = {k: json_float((rec.get("scores") or {}).get(k)) for k in SCORE_COLUMNS}
        ok = rec.get("status") == "ok"
        if not ok:
            scores["n_warnings"] = math.nan
        codes = sorted({w["code"] for w in ((rec.get("evaluation") or {}).get("warnings") or [])})
        defects = defect_codes([{"code": c} for c in codes])
        row: dict[str, Any] = {"shape": job.shape.name, "method": job.method.name, "condition": job.condition.name,
                               "seed": job.seed, "status": rec.get("status", "missing"), "error": rec.get("error", ""),
                               **scores, "seconds": json_float(rec.get("seconds")),
                               "sound": (0 if defects else 1) if ok else "", "defects": ";".join(defects),
                               "warnings": ";".join(codes), "label": rec.get("label", ""),
                               "n_points": rec.get("n_points", ""), "key": job.key}
        for p in profiles:
            v = p.verdict(scores, job.condition.to_dict(), ok=ok, defects=defects)
            row[f"profile_{p.name}"] = v.status
            row[f"profile_{p.name}_score"] = v.score
            row[f"profile_{p.name}_reason"] = v.reason
        rows.append(row)
    return rows


def _cell(v: Any) -> str:
    if isinstance(v, float):
        if math.isnan(v):
            return ""
        return repr(v) if math.isfinite(v) else ("inf" if v > 0 else "-inf")
    return str(v)


def results_csv_text(rows: list[dict[str, Any]], profiles: tuple[Profile, ...]) -> str:
    # the format's version is the last column (skelcore/io/schemas/results_csv.schema.json)
    header = list(COLUMNS) + [f"profile_{p.name}{s}" for p in profiles for s in ("", "_score", "_reason")]
    header.append("schema_version")
    buf = _io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    for r in rows:
        cells = {**r, "schema_version": SCHEMA_VERSION}
        w.writerow([_cell(cells.get(k, "")) for k in header])
    return buf.getvalue()


def write_results_csv(path: str | os.PathLike, rows: list[dict[str, Any]], profiles: tuple[Profile, ...],
                      inputs: tuple[str, ...] = ()) -> None:
    with atomic_open(path, "w", inputs=inputs) as fh:
        fh.write(results_csv_text(rows, profiles))
