"""The Evaluation: every local value (NaN = invalid), both barcodes, overall scores with counts.

Overall scores are derived from the local arrays on demand, so the viewer can change the
thresholds beta* and c* without recomputing anything (docs/metrics.md 2-3: "bounded" is beta > beta*, and an
unbounded element's centeredness is 0).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from .curve import CurveSkeleton
from .geometry import Normalization
from .metrics.coverage import Coverage
from .metrics.ground_truth import GroundTruthComparison
from .metrics.reference import ReferenceComparison
from .metrics.topology import TopologyResult
from .params import Params
from .scan.scan_report import ScanReport
from .diagnostics.trust_warning import TrustWarning

if TYPE_CHECKING:
    from .scores import Scores

# TopologyResult lives beside its metric (metrics.topology); imported from here for compatibility
__all__ = ["TopologyResult", "SkeletalLocal", "CurveLocal", "Evaluation", "apply_unbounded_rule"]


def apply_unbounded_rule(c_raw: np.ndarray, beta: np.ndarray, beta_star: float) -> np.ndarray:
    """docs/metrics.md 3: an element that is not bounded (beta <= beta*) gets c = 0, even where c was NaN."""
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
    vertex (the sampling of docs/metrics.md 3.2). ``curve`` and ``samples`` are in the user's units.
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
    #: the ground-truth metrics against the reference (skelcore.metrics.ground_truth.GroundTruthComparison,
    #: the inputs' units; docs/metrics.md 5.3.1)
    ground_truth: GroundTruthComparison | None = None
    #: what could not be computed and why, e.g. {"topology": "..."}
    not_computed: dict[str, str] = field(default_factory=dict)
    #: the defects found without a reference (skelcore.diagnostics.record.Diagnostics)
    diagnostics: Any = None
    #: real scans (docs/metrics.md 6): viewpoints, stray points, openings; None when no scan option was
    #: given and no scan warning fired
    scan: ScanReport | None = None
    #: how it was made (skelcore.stages.evaluation_source.EvaluationSource: evaluate's arguments and its
    #: stages' context), what :meth:`update` scores an edited curve with; None when built otherwise
    source: Any = field(default=None, repr=False, compare=False)

    # ---- overall scores -------------------------------------------------------------------
    def summary(self, beta_star: float | None = None, c_star: float | None = None) -> dict[str, Any]:
        """Overall scores and counts; thresholds default to the params' (docs/metrics.md 2-4)."""
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

    def scores(self, beta_star: float | None = None, c_star: float | None = None) -> "Scores":
        """The overall scores as one flat record (:class:`skelcore.scores.Scores`), counted with
        beta*, c* (default: the params' thresholds, docs/metrics.md 2-3); the values of :meth:`summary`."""
        from .scores import Scores

        return Scores.from_evaluation(self, beta_star, c_star)

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

    # ---- proofreading: skelcore.edit.incremental, imported when called ----
    def update(self, edited: Any, *, diagnostics: bool = True, scan_checks: bool = True) -> "Evaluation":
        """The Evaluation of the edited curve skeleton (a :class:`skelcore.edit.Change` or the new curve)
        against the same cloud, skeletal set and params; the curve samples whose position and direction
        did not change keep their values (the same as evaluating afresh). ``diagnostics=False`` leaves
        out the curve's coverage, defects and missing parts (the slow part), named in ``not_computed``;
        with it, ``scan_checks=False`` also leaves out the real-scan trust checks (``open_surface``,
        ``thin_parts``, ``sparse_boundedness``: no warnings of theirs), which
        :meth:`complete_update` runs (a repair's first look reads no warning, docs/repair.md)."""
        from .edit.incremental import update_evaluation

        return update_evaluation(self, edited, diagnostics=diagnostics, scan_checks=scan_checks)

    def complete_update(self, cancel: Any = None, scan_checks: bool = True) -> "Evaluation":
        """This ``update(..., diagnostics=False)`` with the curve's coverage, defects and missing parts
        added: equal to ``update(change)`` (a viewer shows the four metrics first, then these); ``self``
        when nothing was left out. ``cancel()`` True stops it (:class:`skelcore.errors.Cancelled`).
        ``scan_checks=False``: without the real-scan trust checks (as :meth:`update`)."""
        from .edit.incremental import complete_update

        return complete_update(self, cancel, scan_checks)

    @property
    def diagnostics_left_out(self) -> tuple[str, ...]:
        """The curve's stages an ``update(diagnostics=False)`` left out (() when none)."""
        from .edit.incremental import left_out

        return left_out(self)

    # ---- serialisation: skelcore.io.evaluation_files, imported when called (the record imports no io) ----
    def to_json_dict(self, version: str | None = None) -> dict[str, Any]:
        """The ``--json`` document of the CLI; null where an input was not given."""
        from .io import evaluation_files

        return evaluation_files.to_json_dict(self, version)

    def write_json(self, path: str, inputs: tuple[str, ...] = ()) -> None:
        """The ``--json`` document, written atomically (never over ``inputs`` or the evaluated files)."""
        from .io import evaluation_files

        evaluation_files.write_json(self, path, inputs)

    def write_per_point(self, prefix: str, inputs: tuple[str, ...] = ()) -> list[str]:
        """``PREFIX_skeletal.csv``, ``PREFIX_curve_samples.csv``, ``PREFIX_curve_vertices.csv`` and,
        with coverage or reverse correspondence, ``PREFIX_cloud.csv`` (one row per cloud point)."""
        from .io import evaluation_files

        return evaluation_files.write_per_point(self, prefix, inputs)

    def cloud_columns(self) -> dict[str, np.ndarray]:
        """Per-cloud-point columns: x, y, z, and gap/covered per coverage, skeletal_row (reverse)."""
        from .io import evaluation_files

        return evaluation_files.cloud_columns(self)

    def write_barcodes(self, path: str, inputs: tuple[str, ...] = ()) -> None:
        """``diagram,birth,death`` rows for every bar of both diagrams (``inf`` for the infinite bar)."""
        from .io import evaluation_files

        evaluation_files.write_barcodes(self, path, inputs)

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


    # ---- pictures and tables (skelcore.display; pyvista, matplotlib, IPython imported when drawing) ----
    def show(self, metric: str = "centeredness", **options):
        """The skeleton coloured by ``metric`` over the faint cloud, with its colour bar (NaN magenta):
        in a notebook's cell, else a window, or a PNG whose path is returned (``path=``, or no display).
        Options: :func:`skelcore.display.show.show`."""
        from .display.show import show

        return show(self, metric, **options)

    def show_barcodes(self, **options):
        """The H0 barcodes of the cloud and the skeletal set (docs/metrics.md 1), where :meth:`show` draws."""
        from .display.show import show_barcodes

        return show_barcodes(self, **options)

    def __repr__(self) -> str:
        """The paper's table as the CLI prints it (:func:`skelcore.display.summary_table.format_table`,
        docs/metrics.md 5.5; 3.3 for the counts), the warning codes and where the data are."""
        from .display.summary_table import _caption, format_table

        try:
            lines = [_caption(self), format_table(self.scores())]
        except Exception as exc:  # a repr must not fail in a console or a debugger
            return f"<Evaluation: no summary ({type(exc).__name__}: {exc})>"
        if repr(self.params) != "Params()":
            lines.insert(1, f"params: {self.params!r}")
        codes = [w.code for w in self.warnings]
        lines.append(f"warnings: {', '.join(codes)}" if codes else "warnings: none")
        if self.not_computed:
            lines.append(f"not computed: {', '.join(self.not_computed)}")
        lines.append("data: .scores() .summary() .warnings .skeletal .curve .to_frame(kind) .to_json_dict() "
                     ".show(metric) .params")
        return "\n".join(lines)

    def _repr_html_(self) -> str:
        """The paper's summary table, the defects and the warnings, for Jupyter."""
        from .display.summary_table import summary_html

        return summary_html(self)
