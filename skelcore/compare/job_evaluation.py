"""A job's whole Evaluation in its ``jobs/KEY.npz``, and the Evaluation rebuilt from it (issue 11).

``evaluation_arrays`` adds, beside the report's float32 pictures' arrays, what a viewer needs to show
the job as if just evaluated, at full precision and with the ``ev_`` prefix: the evaluated (degraded)
cloud, the skeleton outputs (skeletal points, the curve, the skeletal index), the raw local values
(before SPEC 3's unbounded -> 0 rule, so the thresholds can change), the correspondence rows, the
curve samples' edges, the coverage gaps and the normalization. ``evaluation_from_store`` puts them
back together with the record's ``evaluate --json`` document (scores, params, warnings): nothing is
recomputed, and its ``summary()`` gives the stored scores.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from ..curve import CurveSkeleton
from ..errors import SkelInputError
from ..geometry import Normalization
from ..metrics.coverage import Coverage
from ..params import Params
from ..evaluation import CurveLocal, Evaluation, SkeletalLocal, TopologyResult
from ..trust import TrustWarning
from .job_store import json_float

__all__ = ["evaluation_arrays", "evaluation_from_store", "has_evaluation", "STORED_KEY"]

#: present in every npz that holds a whole Evaluation
STORED_KEY = "ev_cloud"

_SKELETAL = ("boundedness", "centeredness_raw", "smoothness", "rows", "centeredness_rows_raw", "index")
_CURVE = ("samples", "sample_edge", "sample_t", "sample_boundedness", "sample_centeredness_raw", "vertex_degree",
          "vertex_smoothness")


def has_evaluation(arrays: dict[str, np.ndarray]) -> bool:
    return STORED_KEY in arrays


def evaluation_arrays(ev: Evaluation) -> dict[str, np.ndarray]:
    """Every array of ``ev`` that its JSON document lacks, under ``ev_`` names (float64 kept)."""
    out: dict[str, np.ndarray] = {
        "ev_cloud": np.asarray(ev.cloud, dtype=float),
        "ev_norm_center": np.asarray(ev.normalization.center, dtype=float),
        "ev_norm_scale": np.array([float(ev.normalization.scale)]),
    }
    if ev.skeletal is not None:
        s = ev.skeletal
        out["ev_skeletal"] = np.asarray(s.points, dtype=float)
        out["ev_skeletal_flags"] = np.array([int(bool(s.centeredness_available)), int(s.source == "curve")])
        for name in _SKELETAL:
            value = getattr(s, name, None)
            if value is not None:
                out[f"ev_skeletal_{name}"] = np.asarray(value)
    if ev.curve is not None:
        c = ev.curve
        out["ev_curve_vertices"] = np.asarray(c.curve.vertices, dtype=float)
        out["ev_curve_edges"] = np.asarray(c.curve.edges, dtype=np.int64).reshape(-1, 2)
        for name in _CURVE:
            out[f"ev_curve_{name}"] = np.asarray(getattr(c, name))
    for kind in ("skeletal", "curve"):
        cov = getattr(ev, f"coverage_{kind}")
        if cov is not None:
            out[f"ev_coverage_{kind}_gap"] = np.asarray(cov.gap, dtype=float)
            out[f"ev_coverage_{kind}_covered"] = np.asarray(cov.covered, dtype=bool)
            out[f"ev_coverage_{kind}_n"] = np.array([int(cov.n_elements)])
    return out


def _params(doc: dict[str, Any]) -> Params:
    raw = dict(doc.get("params") or {})
    known = {f.name for f in dataclasses.fields(Params)}
    return Params(**{k: v for k, v in raw.items() if k in known})


def evaluation_from_store(doc: dict[str, Any], arrays: dict[str, np.ndarray], where: str = "") -> Evaluation:
    """The Evaluation a job stored: ``doc`` is its record's ``evaluation``, ``arrays`` its npz.

    A store written before the whole Evaluation was kept raises a one-line SkelInputError naming ``where``.
    """
    if not has_evaluation(arrays):
        raise SkelInputError("this run stored no skeletons (written by an older skelcore): run skelcore compare "
                             "again into a new --out folder", where or None)
    a = arrays
    ev = Evaluation(params=_params(doc), normalization=Normalization(np.asarray(a["ev_norm_center"], float),
                                                                     float(a["ev_norm_scale"][0])),
                    cloud=np.asarray(a["ev_cloud"], float), correspondence=doc.get("correspondence"))
    inputs = doc.get("inputs") or {}
    ev.inputs = {k: (v.get("path") if isinstance(v, dict) else v) for k, v in inputs.items() if v is not None}
    ev.timings = {k: float(v) for k, v in (doc.get("timings_s") or {}).items()}
    ev.not_computed = dict(doc.get("not_computed") or {})
    ev.warnings = [TrustWarning(w["code"], w["message"]) for w in doc.get("warnings") or []]
    topo = doc.get("topology")
    if topo is not None and "cloud_barcode" in a:
        ev.topology = TopologyResult(json_float(topo.get("bottleneck")), json_float(topo.get("wasserstein")),
                                     json_float(topo.get("eps_star")), int(topo.get("n_bars") or 0),
                                     np.asarray(a["cloud_barcode"], float), np.asarray(a["skeletal_barcode"], float))
    if "ev_skeletal" in a:
        flags = a["ev_skeletal_flags"]
        opt = {n: a[f"ev_skeletal_{n}"] for n in ("rows", "centeredness_rows_raw", "index") if f"ev_skeletal_{n}" in a}
        ev.skeletal = SkeletalLocal(points=np.asarray(a["ev_skeletal"], float),
                                    boundedness=a["ev_skeletal_boundedness"],
                                    centeredness_raw=a["ev_skeletal_centeredness_raw"],
                                    smoothness=a["ev_skeletal_smoothness"], centeredness_available=bool(flags[0]),
                                    source="curve" if flags[1] else "skeletal", **opt)
    if "ev_curve_vertices" in a:
        smooth = (doc.get("smoothness") or {}).get("curve")
        count = ((doc.get("counts") or {}).get("smoothness") or {}).get("curve", 0)
        vertices = np.asarray(a["ev_curve_vertices"], float)
        curve = CurveSkeleton(vertices, np.asarray(a["ev_curve_edges"], np.int64), np.arange(len(vertices)))
        ev.curve = CurveLocal(curve=curve, **{n: a[f"ev_curve_{n}"] for n in _CURVE},
                              smoothness_overall=json_float(smooth), smoothness_count=int(count))
    cov_doc = doc.get("coverage") or {}
    for kind in ("skeletal", "curve"):
        block = cov_doc.get(kind)
        if isinstance(block, dict) and f"ev_coverage_{kind}_gap" in a:
            setattr(ev, f"coverage_{kind}", Coverage(
                gap=a[f"ev_coverage_{kind}_gap"], covered=a[f"ev_coverage_{kind}_covered"],
                fraction=json_float(block.get("fraction")), mean_gap=json_float(block.get("mean_gap")),
                max_gap=json_float(block.get("max_gap")), tau=json_float(cov_doc.get("tau")), slack=json_float(cov_doc.get("slack")),
                n_elements=int(a[f"ev_coverage_{kind}_n"][0])))
    return ev
