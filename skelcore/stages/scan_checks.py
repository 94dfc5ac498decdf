"""The real-scan trust checks, run after the stages (docs/metrics.md 6): ``outliers`` (stray points in
the cloud, found by the "stray points" stage) and ``open_surface`` (openings through which the rays of
otherwise bounded elements escape) and ``thin_parts`` (where the "openings" are parts sampled too
thinly to resolve, a few spacings across: they switch nothing off).

The opening search only runs when some skeleton has at least ``open_surface_share`` of its elements
unbounded (else no opening can change that share), and not with viewpoints (the scores then count
only what the sensors saw).  Without a scan option the Evaluation gets a scan report only when one of
the two warnings fires, so a clean evaluation's document is the paper's.
"""

from __future__ import annotations

import time

import numpy as np

from ..evaluation import Evaluation
from ..geometry import Checkpoint
from ..scan.escape import escaping_share, set_local_radii, skeleton_openings
from ..scan.openings import thin_parts
from ..diagnostics.interior import median_spacing
from ..scan.outliers import local_spacing
from ..scan.scan_report import (ScanReport, open_surface_warning, outliers_warning, sparse_boundedness_warning,
                                 thin_parts_warning)
from ..diagnostics.trust_warning import TrustWarning
from .context import EvalContext

__all__ = ["scan_warnings"]


def scan_warnings(ctx: EvalContext, ev: Evaluation, checkpoint: Checkpoint) -> list[TrustWarning]:
    """``outliers`` and ``open_surface`` for ``ev`` (whose ``scan`` report they fill in)."""
    out: list[TrustWarning] = []
    report = ev.scan if ev.scan is not None else ScanReport()
    strays = ctx.results.get("stray points")  # the stage's; None when remove_outliers found them
    if strays is not None:
        if strays.cloud.count or len(strays.skeletal_rows):
            report.outliers = strays.to_dict()
            out.append(outliers_warning(strays))
    if ctx.viewpoints_n is None:
        out += _open_surface(ctx, ev, report, checkpoint)
        out += _sparse_boundedness(ctx, ev, report)
    if out and ev.scan is None:
        ev.scan = report
    return out


def _columns(ctx: EvalContext, ev: Evaluation) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """(column, its elements normalized, their boundedness) of each skeleton scored."""
    cols = []
    if ev.skeletal is not None:
        cols.append(("skeletal", ctx.norm.apply(ev.skeletal.points), ev.skeletal.boundedness))
    if ev.curve is not None:
        cols.append(("curve", ctx.samples.points, ev.curve.sample_boundedness))
    return cols


def _open_surface(ctx: EvalContext, ev: Evaluation, report: ScanReport, checkpoint: Checkpoint) -> list[TrustWarning]:
    """``open_surface`` from the openings of resolved parts, ``thin_parts`` from the boundary points of
    parts too thin for their sampling (docs/metrics.md 6.1)."""
    p = ctx.params
    cols = [c for c in _columns(ctx, ev) if np.mean(~(np.asarray(c[2]) > p.beta_star)) >= p.open_surface_share]
    if not cols:
        return []
    t0 = time.perf_counter()
    elements = np.vstack([ctx.norm.invert(c[1]) for c in _columns(ctx, ev)])
    capped = {i for i, o in enumerate(report.openings or []) if o.get("capped")}
    if ctx.openings is not None:  # --cap-openings found them
        openings = ctx.openings
        open_now = [o for i, o in enumerate(openings) if i not in capped and len(o.dome)]
        thin_rows = np.zeros(0, np.int64)
    else:
        openings, open_now, thin_rows = skeleton_openings(ctx.cloud, elements, p, checkpoint=checkpoint,
                                                               memo=ctx.openings_memo)
    out: list[TrustWarning] = []
    thin = thin_parts(ctx.cloud, thin_rows, p)
    if thin is not None:
        report.thin_parts = thin
        out.append(thin_parts_warning(thin))
    if not open_now:
        report.timings["open_surface"] = time.perf_counter() - t0
        return out
    set_local_radii(openings, ctx.cloud, elements)
    domes_n = ctx.norm.apply(np.vstack([o.dome for o in open_now]))
    shares = {name: escaping_share(ctx.bounded_cloud_n, domes_n, pts, beta, p, checkpoint=checkpoint)
              for name, pts, beta in cols}
    report.timings["open_surface"] = time.perf_counter() - t0
    if max(shares.values()) < p.open_surface_share:
        return out
    if report.openings is None:
        report.openings = [dict(o.to_dict(), rows=o.rows.tolist(), capped=False, refused=None) for o in openings]
    else:  # --cap-openings found them: now with their local radii
        for entry, o in zip(report.openings, openings):
            entry.update(local_radius=float(o.local_radius), size=float(o.size))
    report.escaping = dict(shares)
    sizes = [o.size for o in open_now if np.isfinite(o.size)]
    return [open_surface_warning([o.kind for o in open_now], max(sizes) if sizes else float("nan"), shares)] + out


def _sparse_boundedness(ctx: EvalContext, ev: Evaluation, report: ScanReport) -> list[TrustWarning]:
    """``sparse_boundedness``: the share of a skeleton's elements that are unbounded where the cloud around
    them (the median spacing of its outlier_local_k nearest points, not the outlier test's lower
    quartile, which a density gradient's denser side sets) is sampled more than ``sparse_ratio`` x as
    sparsely as its median (docs/metrics.md 6.1): the rays
    (2 median spacings wide) pass between the samples there, and the paper's boundedness falls with the
    sampling, not the skeleton.  Switches nothing off."""
    p = ctx.params
    shares: dict[str, float] = {}
    global_spacing = median_spacing(ctx.cloud_n)
    if not global_spacing > 0:
        return []
    for name, pts, beta in _columns(ctx, ev):
        low = np.flatnonzero(~(np.asarray(beta) > p.beta_star))
        if len(beta) == 0 or len(low) < p.open_surface_share * len(beta):
            continue
        near = local_spacing(ctx.cloud_n, np.asarray(pts)[low], int(p.outlier_local_k), quantile=0.5)
        shares[name] = float(np.count_nonzero(near > p.sparse_ratio * global_spacing)) / len(beta)
    if not shares or max(shares.values()) < p.open_surface_share:
        return []
    report.sparse = dict(shares)
    return [sparse_boundedness_warning(shares, p.sparse_ratio)]
