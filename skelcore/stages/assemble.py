"""The Evaluation from the stages' results: the skeletal and curve columns (local values in the user's
units, docs/metrics.md 2-4), coverage, the reference comparison, what was not computed, and the trust checks
(frame, frame fit, smoothness, no correspondence; the real-scan checks of .scan_checks;
docs/metrics.md) run after the stages."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..correspondence import aggregate_rows
from ..evaluation import CurveLocal, Evaluation, SkeletalLocal
from ..geometry import Checkpoint
from ..diagnostics.trust import TrustWarning, frame_fit_warning, frame_warnings, no_correspondence_warning, smoothness_warning
from ..diagnostics.record import diagnostics_record
from .context import EvalContext
from .scan_checks import scan_warnings

__all__ = ["assemble", "trust_warnings", "diagnostics_warnings", "diagnostics_of"]


def assemble(ctx: EvalContext, inputs: dict[str, Any] | None = None) -> Evaluation:
    """The Evaluation of ``ctx`` once every selected stage has stored its result (no trust checks)."""
    got = ctx.results
    ev = Evaluation(params=ctx.params, normalization=ctx.norm, cloud=ctx.cloud, inputs=dict(inputs or {}),
                    correspondence=ctx.mode, not_computed=dict(ctx.not_computed))
    ev.topology = got.get("topology")
    if ctx.skeletal is not None:
        ev.skeletal = _skeletal_local(ctx, ctx.skeletal, ctx.mode, ctx.index)
    if ctx.curve is not None:
        samples = ctx.samples
        s_v, (s_overall, s_count) = got["curve smoothness"]
        ev.curve = CurveLocal(
            curve=ctx.curve,
            samples=ctx.norm.invert(samples.points),
            sample_edge=samples.edge,
            sample_t=samples.t,
            sample_boundedness=got["curve boundedness"],
            sample_centeredness_raw=got["curve centeredness"],
            vertex_degree=ctx.curve.degrees(),
            vertex_smoothness=s_v,
            smoothness_overall=float(s_overall),
            smoothness_count=int(s_count),
        )
    if ctx.from_curve:
        ev.skeletal = _skeletal_local(ctx, ctx.norm.invert(got["correspondence"]), "pointwise", None)
        ev.skeletal.source = "curve"
    ev.coverage_skeletal = got.get("skeletal coverage")
    ev.coverage_curve = got.get("curve coverage")
    ev.reference = got.get("reference")
    ev.ground_truth = got.get("ground truth")
    ev.diagnostics = diagnostics_of(ctx)
    ev.scan = ctx.scan
    return ev


def diagnostics_of(ctx: EvalContext):
    """The diagnostics' record (docs/diagnostics.md) of the stages' results, None when none ran."""
    got = ctx.results
    if not any(k in got for k in ("curve defects", "skeletal outside", "skeletal missing parts", "curve missing parts")):
        return None
    return diagnostics_record(got.get("curve defects"), got.get("skeletal missing parts"),
                              got.get("curve missing parts"), skeletal_outside=got.get("skeletal outside"))


def diagnostics_warnings(ctx: EvalContext) -> list[TrustWarning]:
    """The diagnostics' defect warnings, after the trust checks."""
    out: list[TrustWarning] = []
    for name in ("skeletal missing parts", "curve missing parts", "curve defects", "skeletal outside"):
        found = ctx.results.get(name)
        if found is not None:
            out += found.warnings()
    return out


def _skeletal_local(ctx: EvalContext, points: np.ndarray, mode: str | None, index: np.ndarray | None) -> SkeletalLocal:
    """The skeletal column; under reverse correspondence the per-row centeredness is averaged per point."""
    got = ctx.results
    rows = c_rows = None
    if mode == "none":
        c_raw = np.full(len(points), np.nan)
    elif mode == "reverse":
        rows, c_rows = got["correspondence"], got["skeletal centeredness"]
        c_raw = aggregate_rows(c_rows, rows, len(points))
    else:
        c_raw = got["skeletal centeredness"]
    return SkeletalLocal(
        points=points, boundedness=got["skeletal boundedness"], centeredness_raw=c_raw,
        smoothness=got["skeletal smoothness"], rows=rows, centeredness_rows_raw=c_rows,
        centeredness_available=mode != "none", index=index,
    )  # fmt: skip


def trust_warnings(ctx: EvalContext, ev: Evaluation, checkpoint: Checkpoint, scan: bool = True) -> list[TrustWarning]:
    """SkelScope's trust checks on the given skeletons (docs/metrics.md); ``checkpoint`` is only
    reached by the rare frame-fit re-runs of boundedness. ``scan`` False leaves out the real-scan
    checks (:func:`.scan_checks.scan_warnings`: the openings' search, the dear part at 30k points)."""
    p, cloud = ctx.params, ctx.cloud

    def bounded_fraction(points_user: np.ndarray) -> float:
        beta = ctx.boundedness(ctx.norm.apply(points_user), checkpoint)
        return float(np.mean(beta > p.beta_star))

    out: list[TrustWarning] = []
    box = ctx.cloud_box(p.trust_extent_quantile)
    if ctx.skeletal is not None:
        found = frame_warnings(cloud, ctx.skeletal, "skeletal point set", p, cloud_box=box)
        if not found:
            now = float(np.mean(ev.skeletal.boundedness > p.beta_star))
            found = frame_fit_warning(cloud, ctx.skeletal, now, bounded_fraction, "skeletal point set", p)
        out += found
    if ctx.curve is not None:
        found = frame_warnings(cloud, ctx.curve.vertices, "curve skeleton", p, cloud_box=box)
        if not found:
            now = float(np.mean(ev.curve.sample_boundedness > p.beta_star))
            found = frame_fit_warning(cloud, ev.curve.samples, now, bounded_fraction, "curve skeleton", p)
        out += found
        out += smoothness_warning(ev.curve.vertex_degree)
    if ctx.mode == "none":
        out.append(no_correspondence_warning(len(ctx.skeletal), len(cloud)))
    if scan:
        out += scan_warnings(ctx, ev, checkpoint)
    return out
