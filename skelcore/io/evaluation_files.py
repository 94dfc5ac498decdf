"""An Evaluation saved and loaded, as a symmetric pair: the files written here are read back
here into an equal Evaluation.

- ``to_json_dict`` / ``write_json``: the ``evaluate --json`` document (scores, counts, params, inputs,
  warnings, coverage, reference, ground truth, timings, the real-scan report; docs/metrics.md 5.5), also each compare job's
  ``evaluation`` record.
- ``write_per_point``, ``cloud_columns``, ``write_barcodes``: the CSVs (NaN written ``nan``).
- ``evaluation_arrays``: what the document lacks, for an npz (compare's ``jobs/KEY.npz``): the cloud,
  the skeletons, the raw local values (before the unbounded -> 0 rule of docs/metrics.md 3.3, so thresholds can change),
  the correspondence rows, the curve samples' edges, the coverage gaps, the normalization, the
  barcodes, at full precision under ``ev_`` names; ``ev_meta`` keeps the inputs and the timings exactly.
- ``evaluation_from_store``: the document and the arrays put back together, nothing recomputed;
  ``save_evaluation`` / ``load_evaluation`` do the same with a JSON and an npz file.

Stores written before ``ev_meta`` or ``ev_curve_vertex_map`` existed still read (inputs from the
document, timings to the microsecond). All writes are atomic (:mod:`.atomic`).
"""

from __future__ import annotations

import csv
import dataclasses
import json
import math
import os
from typing import Any, Iterable

import numpy as np

from ..curve import CurveSkeleton
from ..errors import SkelInputError
from ..evaluation import CurveLocal, Evaluation, SkeletalLocal
from ..geometry import Normalization
from ..metrics.coverage import Coverage
from ..metrics.ground_truth import GroundTruthComparison
from ..metrics.reference import ReferenceComparison
from ..metrics.topology import TopologyResult
from ..params import Params
from ..scan.scan_report import ScanReport
from ..diagnostics.trust_warning import TrustWarning
from .atomic import atomic_open
from .json_numbers import json_float, json_safe
from .schemas import SCHEMA_VERSION

__all__ = [
    "to_json_dict", "write_json", "write_per_point", "cloud_columns", "write_barcodes",
    "evaluation_arrays", "evaluation_from_store", "has_evaluation", "STORED_KEY",
    "save_evaluation", "load_evaluation",
]  # fmt: skip

#: present in every npz that holds a whole Evaluation
STORED_KEY = "ev_cloud"

_SKELETAL = ("boundedness", "centeredness_raw", "smoothness", "rows", "centeredness_rows_raw", "index")
_CURVE = ("samples", "sample_edge", "sample_t", "sample_boundedness", "sample_centeredness_raw", "vertex_degree",
          "vertex_smoothness")


# ---- the JSON document ------------------------------------------------------------------------
def to_json_dict(ev: Evaluation, version: str | None = None) -> dict[str, Any]:
    """The ``--json`` document of the CLI; null where an input was not given."""
    from ..version import __version__

    summ = ev.summary()
    params = ev.params.to_dict()
    params["boundedness_estimator"] = ev.params.boundedness_method
    doc = {
        "schema_version": SCHEMA_VERSION,  # the format's (skelcore/io/schemas/evaluation.schema.json)
        "skelcore_version": version or __version__,
        "params": params,
        "inputs": {
            "cloud": {"path": ev.inputs.get("cloud"), "n_points": int(len(ev.cloud))},
            "skeletal": None
            if ev.skeletal is None
            else {"path": ev.inputs.get("skeletal"), "n_points": int(len(ev.skeletal.points)),
                  "source": ev.skeletal.source},
            "curve": None
            if ev.curve is None
            else {
                "path": ev.inputs.get("curve"),
                "n_vertices": ev.curve.curve.n_vertices,
                "n_edges": ev.curve.curve.n_edges,
            },
            "skeletal_index": ev.inputs.get("skeletal_index"),
            "reference_curve": ev.inputs.get("reference_curve"),
        },
        "topology": summ["topology"],
        "boundedness": summ["boundedness"],
        "centeredness": summ["centeredness"],
        "smoothness": summ["smoothness"],
        "counts": summ["counts"],
        "correspondence": ev.correspondence,
        "not_computed": dict(ev.not_computed),
        "warnings": ev.warning_dicts(),
        "coverage": summ["coverage"],
        "reference": None if ev.reference is None else ev.reference.to_dict(),
        "ground_truth": None if ev.ground_truth is None else ev.ground_truth.to_dict(),
        "diagnostics": None if ev.diagnostics is None else ev.diagnostics.to_dict(),
        "timings_s": {k: round(float(v), 6) for k, v in ev.timings.items()},
    }
    if ev.scan is not None:  # only with a scan option or a scan warning (docs/metrics.md 6)
        doc["scan"] = ev.scan.to_dict()
    return json_safe(doc)


def write_json(ev: Evaluation, path: str | os.PathLike, inputs: tuple[str, ...] = ()) -> None:
    with atomic_open(path, "w", inputs=inputs or ev._input_paths()) as fh:
        json.dump(to_json_dict(ev), fh, indent=2)
        fh.write("\n")


# ---- the CSVs -----------------------------------------------------------------------------------
def write_per_point(ev: Evaluation, prefix: str, inputs: tuple[str, ...] = ()) -> list[str]:
    """``PREFIX_skeletal.csv``, ``PREFIX_curve_samples.csv``, ``PREFIX_curve_vertices.csv`` and,
    with coverage or reverse correspondence, ``PREFIX_cloud.csv`` (one row per cloud point)."""
    written: list[str] = []
    guard = inputs or ev._input_paths()
    b_star = ev.params.beta_star
    if ev.skeletal is not None:
        s = ev.skeletal
        path = f"{prefix}_skeletal.csv"
        rows = zip(range(len(s.points)), *s.points.T, s.boundedness, s.centeredness(b_star), s.smoothness)
        extra, cols = _skeletal_defect_column(ev, len(s.points))
        _write_csv(path, ["index", "x", "y", "z", "boundedness", "centeredness", "smoothness", *cols],
                   (r + e for r, e in zip(rows, extra)), guard)
        written.append(path)
    if ev.curve is not None:
        c = ev.curve
        path = f"{prefix}_curve_samples.csv"
        rows = zip(
            range(len(c.samples)), c.sample_edge, c.sample_t, *c.samples.T,
            c.sample_boundedness, c.sample_centeredness(b_star),
        )
        extra, cols = _defect_columns(ev, "sample", len(c.samples))
        _write_csv(path, ["sample", "edge", "t", "x", "y", "z", "boundedness", "centeredness", *cols],
                   (r + e for r, e in zip(rows, extra)), guard)
        written.append(path)
        path = f"{prefix}_curve_vertices.csv"
        rows = zip(range(c.curve.n_vertices), *c.curve.vertices.T, c.vertex_degree, c.vertex_smoothness)
        extra, cols = _defect_columns(ev, "vertex", c.curve.n_vertices)
        _write_csv(path, ["vertex", "x", "y", "z", "degree", "smoothness", *cols], (r + e for r, e in zip(rows, extra)),
                   guard)
        written.append(path)
    cloud_cols = cloud_columns(ev)
    if len(cloud_cols) > 3:
        path = f"{prefix}_cloud.csv"
        rows = zip(range(len(ev.cloud)), *cloud_cols.values())
        _write_csv(path, ["index", *cloud_cols], rows, guard)
        written.append(path)
    return written


def cloud_columns(ev: Evaluation) -> dict[str, np.ndarray]:
    """Per-cloud-point columns: x, y, z, and gap/covered per coverage, skeletal_row (reverse)."""
    cols: dict[str, np.ndarray] = {"x": ev.cloud[:, 0], "y": ev.cloud[:, 1], "z": ev.cloud[:, 2]}
    for name, cov in (("skeletal", ev.coverage_skeletal), ("curve", ev.coverage_curve)):
        if cov is not None:
            cols[f"gap_{name}"] = cov.gap
            cols[f"covered_{name}"] = cov.covered.astype(np.int64)
    if ev.skeletal is not None and ev.skeletal.rows is not None:
        cols["skeletal_row"] = ev.skeletal.rows
    arrays = {} if ev.diagnostics is None else ev.diagnostics.arrays
    for kind in ("skeletal", "curve"):
        if f"cloud_missing_{kind}" in arrays:
            cols[f"missing_{kind}"] = arrays[f"cloud_missing_{kind}"]
    return cols


def _defect_columns(ev: Evaluation, element: str, n: int) -> tuple[list[tuple], list[str]]:
    """The diagnostics' ``branch`` and ``defects`` (";"-joined codes) per curve sample or vertex."""
    arrays = {} if ev.diagnostics is None else ev.diagnostics.arrays
    if f"curve_{element}_branch" not in arrays:
        return [()] * n, []
    from ..diagnostics.record import defect_names

    return (list(zip(arrays[f"curve_{element}_branch"], defect_names(arrays[f"curve_{element}_defects"]))),
            ["branch", "defects"])


def _skeletal_defect_column(ev: Evaluation, n: int) -> tuple[list[tuple], list[str]]:
    """The diagnostics' ``defects`` per given skeletal point (``outside``)."""
    arrays = {} if ev.diagnostics is None else ev.diagnostics.arrays
    bits = arrays.get("skeletal_point_defects")
    if bits is None or len(bits) != n:
        return [()] * n, []
    from ..diagnostics.record import defect_names

    return [(d,) for d in defect_names(bits)], ["defects"]


def write_barcodes(ev: Evaluation, path: str | os.PathLike, inputs: tuple[str, ...] = ()) -> None:
    """``diagram,birth,death`` rows for every bar of both diagrams (``inf`` for the infinite bar)."""
    if ev.topology is None:
        raise ValueError("no barcodes: a skeletal point set is needed for topological similarity")
    rows = []
    for name, bars in (("cloud", ev.topology.cloud_barcode), ("skeletal", ev.topology.skeletal_barcode)):
        rows.extend((name, float(b), float(d)) for b, d in bars)
    _write_csv(path, ["diagram", "birth", "death"], rows, inputs or ev._input_paths())


def _fmt(value: Any) -> str:
    if isinstance(value, (float, np.floating)):
        v = float(value)
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(value, np.integer):
        return str(int(value))
    return str(value)


def _write_csv(path: str | os.PathLike, header: list[str], rows: Iterable, inputs: Iterable[str]) -> None:
    with atomic_open(path, "w", inputs=inputs) as fh:
        writer = csv.writer(fh, lineterminator="\n")
        writer.writerow(header)
        for row in rows:
            writer.writerow([_fmt(v) for v in row])


# ---- the arrays (compare's npz) and the Evaluation rebuilt ---------------------------------------
def has_evaluation(arrays: dict[str, np.ndarray]) -> bool:
    return STORED_KEY in arrays


def evaluation_arrays(ev: Evaluation) -> dict[str, np.ndarray]:
    """Every array of ``ev`` that its JSON document lacks, under ``ev_`` names (float64 kept), the
    barcodes, and ``ev_meta`` (the inputs and timings as JSON text)."""
    meta = json.dumps({"inputs": ev.inputs, "timings": ev.timings}, default=str)
    out: dict[str, np.ndarray] = {
        "ev_cloud": np.asarray(ev.cloud, dtype=float),
        "ev_norm_center": np.asarray(ev.normalization.center, dtype=float),
        "ev_norm_scale": np.array([float(ev.normalization.scale)]),
        "ev_meta": np.array(meta),
    }
    if ev.topology is not None:
        out["cloud_barcode"] = np.asarray(ev.topology.cloud_barcode, np.float64)
        out["skeletal_barcode"] = np.asarray(ev.topology.skeletal_barcode, np.float64)
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
        if c.curve.vertex_map is not None:
            out["ev_curve_vertex_map"] = np.asarray(c.curve.vertex_map)
        for name in _CURVE:
            out[f"ev_curve_{name}"] = np.asarray(getattr(c, name))
    for kind in ("skeletal", "curve"):
        cov = getattr(ev, f"coverage_{kind}")
        if cov is not None:
            out[f"ev_coverage_{kind}_gap"] = np.asarray(cov.gap, dtype=float)
            out[f"ev_coverage_{kind}_covered"] = np.asarray(cov.covered, dtype=bool)
            out[f"ev_coverage_{kind}_n"] = np.array([int(cov.n_elements)])
    if ev.diagnostics is not None:
        out.update({f"ev_diag_{k}": np.asarray(v) for k, v in ev.diagnostics.arrays.items()})
    return out


def _params(doc: dict[str, Any]) -> Params:
    raw = dict(doc.get("params") or {})
    known = {f.name for f in dataclasses.fields(Params)}
    return Params(**{k: v for k, v in raw.items() if k in known})


def _inputs_and_timings(doc: dict[str, Any], a: dict[str, np.ndarray]) -> tuple[dict[str, Any], dict[str, float]]:
    if "ev_meta" in a:
        meta = json.loads(str(a["ev_meta"][()]))
        return dict(meta["inputs"]), {k: float(v) for k, v in meta["timings"].items()}
    inputs = doc.get("inputs") or {}  # a store written before ev_meta: the document's paths
    return ({k: (v.get("path") if isinstance(v, dict) else v) for k, v in inputs.items() if v is not None},
            {k: float(v) for k, v in (doc.get("timings_s") or {}).items()})


def _reference(block: Any) -> ReferenceComparison | None:
    if not isinstance(block, dict):
        return None
    pair = lambda k: tuple(int(x) for x in block[k])  # noqa: E731
    return ReferenceComparison(
        chamfer=json_float(block["chamfer"]), hausdorff=json_float(block["hausdorff"]),
        precision=json_float(block["precision"]), recall=json_float(block["recall"]), f1=json_float(block["f1"]),
        junctions=pair("junctions"), endpoints=pair("endpoints"), components=pair("components"),
        cycles=pair("cycles"), tau=json_float(block["tau"]))  # fmt: skip


def evaluation_from_store(doc: dict[str, Any], arrays: dict[str, np.ndarray], where: str = "") -> Evaluation:
    """The Evaluation saved as ``doc`` (its ``evaluate --json`` document, a compare record's
    ``evaluation``) and ``arrays`` (:func:`evaluation_arrays`, a job's npz); nothing is recomputed.

    A store written before the whole Evaluation was kept raises a one-line SkelInputError naming ``where``.
    """
    if not has_evaluation(arrays):
        raise SkelInputError("this run stored no skeletons (written by an older skelcore): run skelcore compare "
                             "again into a new --out folder", where or None)
    a = arrays
    ev = Evaluation(params=_params(doc), normalization=Normalization(np.asarray(a["ev_norm_center"], float),
                                                                     float(a["ev_norm_scale"][0])),
                    cloud=np.asarray(a["ev_cloud"], float), correspondence=doc.get("correspondence"))
    ev.inputs, ev.timings = _inputs_and_timings(doc, a)
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
        vertex_map = a["ev_curve_vertex_map"] if "ev_curve_vertex_map" in a else np.arange(len(vertices))
        curve = CurveSkeleton(vertices, np.asarray(a["ev_curve_edges"], np.int64), vertex_map)
        ev.curve = CurveLocal(curve=curve, **{n: a[f"ev_curve_{n}"] for n in _CURVE},
                              smoothness_overall=json_float(smooth), smoothness_count=int(count))
    cov_doc = doc.get("coverage") or {}
    for kind in ("skeletal", "curve"):
        block = cov_doc.get(kind)
        if isinstance(block, dict) and f"ev_coverage_{kind}_gap" in a:
            setattr(ev, f"coverage_{kind}", Coverage(
                gap=a[f"ev_coverage_{kind}_gap"], covered=a[f"ev_coverage_{kind}_covered"],
                fraction=json_float(block.get("fraction")), mean_gap=json_float(block.get("mean_gap")),
                max_gap=json_float(block.get("max_gap")), tau=json_float(cov_doc.get("tau")),
                slack=json_float(cov_doc.get("slack")), n_elements=int(a[f"ev_coverage_{kind}_n"][0])))
    ev.reference = _reference(doc.get("reference"))
    if isinstance(doc.get("ground_truth"), dict):
        ev.ground_truth = GroundTruthComparison.from_dict(doc["ground_truth"])
    if doc.get("diagnostics") is not None:
        from ..diagnostics.record import Diagnostics

        ev.diagnostics = Diagnostics(summary=doc["diagnostics"],
                                     arrays={k[len("ev_diag_"):]: a[k] for k in a if k.startswith("ev_diag_")})
    if isinstance(doc.get("scan"), dict):
        ev.scan = ScanReport.from_dict(doc["scan"])
    return ev


# ---- both files at once ---------------------------------------------------------------------------
def save_evaluation(ev: Evaluation, npz_path: str | os.PathLike, json_path: str | os.PathLike,
                    inputs: tuple[str, ...] = ()) -> None:
    """The ``--json`` document at ``json_path`` and :func:`evaluation_arrays` at ``npz_path``."""
    with atomic_open(npz_path, "wb", inputs=inputs or ev._input_paths()) as fh:
        np.savez_compressed(fh, **evaluation_arrays(ev))
    write_json(ev, json_path, inputs)


def load_evaluation(npz_path: str | os.PathLike, json_path: str | os.PathLike) -> Evaluation:
    """The Evaluation :func:`save_evaluation` wrote (one-line SkelInputError naming a bad file)."""
    try:
        with open(json_path, encoding="utf-8") as fh:
            doc = json.load(fh)
    except (OSError, ValueError) as exc:
        raise SkelInputError(f"cannot read the evaluation document ({exc})", json_path) from None
    if not isinstance(doc, dict):
        raise SkelInputError("not an evaluation document (expected a JSON object)", json_path)
    try:
        with np.load(npz_path) as z:
            arrays = {k: z[k] for k in z.files}
    except (OSError, ValueError) as exc:
        raise SkelInputError(f"cannot read the evaluation arrays ({exc})", npz_path) from None
    if not has_evaluation(arrays):
        raise SkelInputError(f"no Evaluation in these arrays (no {STORED_KEY})", npz_path)
    return evaluation_from_store(doc, arrays, where=str(npz_path))
