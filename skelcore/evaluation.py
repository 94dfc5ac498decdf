"""The Evaluation: every local value (NaN = invalid), both barcodes, overall scores with counts.

Overall scores are derived from the local arrays on demand, so the viewer can change the
thresholds beta* and c* without recomputing anything (SPEC 2-3: "bounded" is beta > beta*, and an
unbounded element's centeredness is 0).
"""

from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .curve import CurveSkeleton
from .geometry import Normalization
from .io.atomic import atomic_open
from .metrics.coverage import Coverage
from .metrics.reference import ReferenceComparison
from .params import Params
from .trust import TrustWarning

__all__ = ["TopologyResult", "SkeletalLocal", "CurveLocal", "Evaluation", "apply_unbounded_rule"]


@dataclass
class TopologyResult:
    """SPEC 1. Barcodes are (n, 2) arrays of (birth, death) in normalized units, longest first,
    the infinite bar first with death = inf; every bar, not only the K compared ones."""

    bottleneck: float
    wasserstein: float
    eps_star: float
    n_bars: int
    cloud_barcode: np.ndarray
    skeletal_barcode: np.ndarray


def apply_unbounded_rule(c_raw: np.ndarray, beta: np.ndarray, beta_star: float) -> np.ndarray:
    """SPEC 3: an element that is not bounded (beta <= beta*) gets c = 0, even where c was NaN."""
    c = np.array(c_raw, dtype=float, copy=True)
    c[~(np.asarray(beta) > beta_star)] = 0.0
    return c


@dataclass
class SkeletalLocal:
    """Local values per skeletal point; ``points`` in the user's units.

    Under reverse correspondence ``rows[i]`` is the skeletal row cloud row i was projected to and
    ``centeredness_rows_raw`` the raw centeredness of that pointwise set (one per cloud row, what
    the overall score counts); ``centeredness_raw`` is its mean over each point's cloud rows.
    ``centeredness_available`` is False when no correspondence exists (then it is all NaN).
    ``source`` is "curve" when the points are the cloud's projections onto the curve skeleton.
    Under index correspondence ``index[i]`` is the cloud row skeletal point i corresponds to (kept so
    a viewer can draw the neighbourhood behind the value).
    """

    points: np.ndarray
    boundedness: np.ndarray
    centeredness_raw: np.ndarray
    smoothness: np.ndarray
    rows: np.ndarray | None = None
    centeredness_rows_raw: np.ndarray | None = None
    centeredness_available: bool = True
    source: str = "skeletal"
    index: np.ndarray | None = None

    def centeredness(self, beta_star: float) -> np.ndarray:
        return apply_unbounded_rule(self.centeredness_raw, self.boundedness, beta_star)

    def centeredness_counted(self, beta_star: float) -> np.ndarray:
        """The values the overall score counts: per cloud row under reverse correspondence."""
        if self.rows is None or self.centeredness_rows_raw is None:
            return self.centeredness(beta_star)
        return apply_unbounded_rule(self.centeredness_rows_raw, self.boundedness[self.rows], beta_star)


@dataclass
class CurveLocal:
    """Local values per curve sample (boundedness, centeredness) and per vertex (smoothness).

    Sample i lies on edge ``sample_edge[i]`` at fraction ``sample_t[i]`` from its lower-index
    vertex (SPEC 3 sampling). ``curve`` and ``samples`` are in the user's units.
    """

    curve: CurveSkeleton
    samples: np.ndarray
    sample_edge: np.ndarray
    sample_t: np.ndarray
    sample_boundedness: np.ndarray
    sample_centeredness_raw: np.ndarray
    vertex_degree: np.ndarray
    vertex_smoothness: np.ndarray
    smoothness_overall: float
    smoothness_count: int

    def sample_centeredness(self, beta_star: float) -> np.ndarray:
        return apply_unbounded_rule(self.sample_centeredness_raw, self.sample_boundedness, beta_star)


def _fraction_above(values: np.ndarray, threshold: float, *, denominator: str) -> tuple[float, int]:
    """Fraction of values > threshold. denominator 'all' counts every element, 'valid' only non-NaN."""
    values = np.asarray(values, dtype=float)
    valid = np.isfinite(values)
    n = int(values.size if denominator == "all" else valid.sum())
    if n == 0:
        return math.nan, 0
    return float(np.count_nonzero(values[valid] > threshold) / n), n


@dataclass
class Evaluation:
    """Result of :func:`skelcore.evaluate`."""

    params: Params
    normalization: Normalization
    cloud: np.ndarray
    topology: TopologyResult | None = None
    skeletal: SkeletalLocal | None = None
    curve: CurveLocal | None = None
    timings: dict[str, float] = field(default_factory=dict)
    inputs: dict[str, Any] = field(default_factory=dict)
    #: "pointwise" | "index" | "reverse" | "none" (skelcore.correspondence.MODES); None: no skeletal set
    correspondence: str | None = None
    warnings: list[TrustWarning] = field(default_factory=list)
    coverage_skeletal: Coverage | None = None
    coverage_curve: Coverage | None = None
    reference: ReferenceComparison | None = None
    #: what could not be computed and why, e.g. {"topology": "..."}
    not_computed: dict[str, str] = field(default_factory=dict)

    # ---- overall scores -------------------------------------------------------------------
    def summary(self, beta_star: float | None = None, c_star: float | None = None) -> dict[str, Any]:
        """Overall scores and counts; thresholds default to the params' (SPEC 2-4)."""
        b_star = self.params.beta_star if beta_star is None else float(beta_star)
        c_star_ = self.params.c_star if c_star is None else float(c_star)
        out: dict[str, Any] = {
            "topology": None,
            "boundedness": {"skeletal": None, "curve": None},
            "centeredness": {"skeletal": None, "curve": None},
            "smoothness": {"skeletal": None, "curve": None},
            "counts": {
                "boundedness": {"skeletal": 0, "curve": 0},
                "centeredness": {"skeletal": 0, "curve": 0},
                "smoothness": {"skeletal": 0, "curve": 0},
            },
        }
        if self.topology is not None:
            t = self.topology
            out["topology"] = {
                "bottleneck": t.bottleneck,
                "wasserstein": t.wasserstein,
                "eps_star": t.eps_star,
                "n_bars": t.n_bars,
            }
        if self.skeletal is not None:
            s = self.skeletal
            b, nb = _fraction_above(s.boundedness, b_star, denominator="all")
            finite = s.smoothness[np.isfinite(s.smoothness)]
            out["boundedness"]["skeletal"], out["counts"]["boundedness"]["skeletal"] = b, nb
            if s.centeredness_available:
                c, nc = _fraction_above(s.centeredness_counted(b_star), c_star_, denominator="all")
                out["centeredness"]["skeletal"], out["counts"]["centeredness"]["skeletal"] = c, nc
            out["smoothness"]["skeletal"] = float(finite.mean()) if finite.size else math.nan
            out["counts"]["smoothness"]["skeletal"] = int(finite.size)
        if self.curve is not None:
            cv = self.curve
            b, nb = _fraction_above(cv.sample_boundedness, b_star, denominator="all")
            c, nc = _fraction_above(cv.sample_centeredness(b_star), c_star_, denominator="valid")
            out["boundedness"]["curve"], out["counts"]["boundedness"]["curve"] = b, nb
            out["centeredness"]["curve"], out["counts"]["centeredness"]["curve"] = c, nc
            out["smoothness"]["curve"] = cv.smoothness_overall
            out["counts"]["smoothness"]["curve"] = cv.smoothness_count
        out["coverage"] = self.coverage_dict()
        return out

    def coverage_dict(self) -> dict[str, Any] | None:
        """JSON ``coverage`` block: {skeletal, curve: {fraction, mean_gap, max_gap} | None, slack, tau}."""
        covs = [c for c in (self.coverage_skeletal, self.coverage_curve) if c is not None]
        if not covs:
            return None
        return {
            "skeletal": None if self.coverage_skeletal is None else self.coverage_skeletal.to_dict(),
            "curve": None if self.coverage_curve is None else self.coverage_curve.to_dict(),
            "slack": covs[0].slack,
            "tau": covs[0].tau,
        }

    def warning_dicts(self) -> list[dict[str, str]]:
        return [w.to_dict() for w in self.warnings]

    # ---- serialisation --------------------------------------------------------------------
    def to_json_dict(self, version: str | None = None) -> dict[str, Any]:
        """The ``--json`` document of the CLI (issue 2); null where an input was not given."""
        from .version import __version__

        summ = self.summary()
        params = self.params.to_dict()
        params["boundedness_estimator"] = self.params.boundedness_method
        doc = {
            "skelcore_version": version or __version__,
            "params": params,
            "inputs": {
                "cloud": {"path": self.inputs.get("cloud"), "n_points": int(len(self.cloud))},
                "skeletal": None
                if self.skeletal is None
                else {"path": self.inputs.get("skeletal"), "n_points": int(len(self.skeletal.points)),
                      "source": self.skeletal.source},
                "curve": None
                if self.curve is None
                else {
                    "path": self.inputs.get("curve"),
                    "n_vertices": self.curve.curve.n_vertices,
                    "n_edges": self.curve.curve.n_edges,
                },
                "skeletal_index": self.inputs.get("skeletal_index"),
                "reference_curve": self.inputs.get("reference_curve"),
            },
            "topology": summ["topology"],
            "boundedness": summ["boundedness"],
            "centeredness": summ["centeredness"],
            "smoothness": summ["smoothness"],
            "counts": summ["counts"],
            "correspondence": self.correspondence,
            "not_computed": dict(self.not_computed),
            "warnings": self.warning_dicts(),
            "coverage": summ["coverage"],
            "reference": None if self.reference is None else self.reference.to_dict(),
            "timings_s": {k: round(float(v), 6) for k, v in self.timings.items()},
        }
        return _json_safe(doc)

    def write_json(self, path: str, inputs: tuple[str, ...] = ()) -> None:
        with atomic_open(path, "w", inputs=inputs or self._input_paths()) as fh:
            json.dump(self.to_json_dict(), fh, indent=2)
            fh.write("\n")

    def write_per_point(self, prefix: str, inputs: tuple[str, ...] = ()) -> list[str]:
        """``PREFIX_skeletal.csv``, ``PREFIX_curve_samples.csv``, ``PREFIX_curve_vertices.csv`` and,
        with coverage or reverse correspondence, ``PREFIX_cloud.csv`` (one row per cloud point)."""
        written: list[str] = []
        guard = inputs or self._input_paths()
        b_star = self.params.beta_star
        if self.skeletal is not None:
            s = self.skeletal
            path = f"{prefix}_skeletal.csv"
            rows = zip(range(len(s.points)), *s.points.T, s.boundedness, s.centeredness(b_star), s.smoothness)
            _write_csv(path, ["index", "x", "y", "z", "boundedness", "centeredness", "smoothness"], rows, guard)
            written.append(path)
        if self.curve is not None:
            c = self.curve
            path = f"{prefix}_curve_samples.csv"
            rows = zip(
                range(len(c.samples)), c.sample_edge, c.sample_t, *c.samples.T,
                c.sample_boundedness, c.sample_centeredness(b_star),
            )
            _write_csv(path, ["sample", "edge", "t", "x", "y", "z", "boundedness", "centeredness"], rows, guard)
            written.append(path)
            path = f"{prefix}_curve_vertices.csv"
            rows = zip(range(c.curve.n_vertices), *c.curve.vertices.T, c.vertex_degree, c.vertex_smoothness)
            _write_csv(path, ["vertex", "x", "y", "z", "degree", "smoothness"], rows, guard)
            written.append(path)
        cloud_cols = self.cloud_columns()
        if len(cloud_cols) > 3:
            path = f"{prefix}_cloud.csv"
            rows = zip(range(len(self.cloud)), *cloud_cols.values())
            _write_csv(path, ["index", *cloud_cols], rows, guard)
            written.append(path)
        return written

    def cloud_columns(self) -> dict[str, np.ndarray]:
        """Per-cloud-point columns: x, y, z, and gap/covered per coverage, skeletal_row (reverse)."""
        cols: dict[str, np.ndarray] = {"x": self.cloud[:, 0], "y": self.cloud[:, 1], "z": self.cloud[:, 2]}
        for name, cov in (("skeletal", self.coverage_skeletal), ("curve", self.coverage_curve)):
            if cov is not None:
                cols[f"gap_{name}"] = cov.gap
                cols[f"covered_{name}"] = cov.covered.astype(np.int64)
        if self.skeletal is not None and self.skeletal.rows is not None:
            cols["skeletal_row"] = self.skeletal.rows
        return cols

    def write_barcodes(self, path: str, inputs: tuple[str, ...] = ()) -> None:
        """``diagram,birth,death`` rows for every bar of both diagrams (``inf`` for the infinite bar)."""
        if self.topology is None:
            raise ValueError("no barcodes: a skeletal point set is needed for topological similarity")
        rows = []
        for name, bars in (("cloud", self.topology.cloud_barcode), ("skeletal", self.topology.skeletal_barcode)):
            rows.extend((name, float(b), float(d)) for b, d in bars)
        _write_csv(path, ["diagram", "birth", "death"], rows, inputs or self._input_paths())

    def _input_paths(self) -> tuple[str, ...]:
        return tuple(str(p) for p in self.inputs.values() if p)

    # ---- other libraries' objects (skelcore.interop; each imports its library only when called) ----
    def to_frame(self, kind: str = "skeletal", **thresholds):
        """A pandas DataFrame, one row per element of ``kind`` ("skeletal", "curve_samples",
        "curve_vertices", "cloud") with every local value and flag (:func:`skelcore.interop.tables.to_frame`)."""
        from .interop.tables import to_frame

        return to_frame(self, kind, **thresholds)

    def to_networkx(self, **thresholds):
        """The curve skeleton as a networkx Graph with the local values as node and edge attributes."""
        from .interop.graph_out import to_networkx

        return to_networkx(self, **thresholds)

    def to_open3d(self, metric: str = "centeredness", **options):
        """The curve skeleton as an Open3D LineSet coloured like the viewer (NaN magenta)."""
        from .interop.open3d_out import to_open3d

        return to_open3d(self, metric, **options)


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


def _write_csv(path: str, header: list[str], rows, inputs) -> None:
    with atomic_open(path, "w", inputs=inputs) as fh:
        writer = csv.writer(fh, lineterminator="\n")
        writer.writerow(header)
        for row in rows:
            writer.writerow([_fmt(v) for v in row])


def _json_safe(obj: Any) -> Any:
    """NaN/inf are not JSON: NaN -> null, inf -> "inf"."""
    if isinstance(obj, dict):
        return {k: _json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_json_safe(v) for v in obj]
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
