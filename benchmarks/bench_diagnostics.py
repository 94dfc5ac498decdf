"""The diagnostics alone: the evaluation's three diagnostics stages (curve defects, skeletal and curve
missing parts; docs/diagnostics.md) run one after the other on an evaluation's inputs, with the curve
boundedness and coverage they read taken from that evaluation (made once, untimed), as the
evaluation's orchestrator calls them. Cases: the hammer with the built-in skeleton, the torus at 100k."""

from __future__ import annotations

import pytest

from skelcore import Params, evaluate
from skelcore.geometry import no_checkpoint
from skelcore.stages.catalogue import CATALOGUE
from skelcore.stages.context import build_context

DIAG = ("curve defects", "skeletal missing parts", "curve missing parts")


def _diagnostics(benchmark, measure, cloud, skeletal, curve, rounds: int) -> None:
    params = Params()
    ev = evaluate(cloud, skeletal, curve, params)

    def context():
        ctx = build_context(cloud, skeletal, curve, params, skeletal_index=None, correspondence="auto",
                            reference_curve=None)
        if ev.curve is not None:
            ctx.results["curve boundedness"] = ev.curve.sample_boundedness
        for key, cov in (("skeletal coverage", ev.coverage_skeletal), ("curve coverage", ev.coverage_curve)):
            if cov is not None:
                ctx.results[key] = cov
        return (ctx,), {}

    def run(ctx):
        ran = []
        for stage in CATALOGUE:
            if stage.name in DIAG and stage.applies(ctx):
                stage.fn(ctx, no_checkpoint)
                ran.append(stage.name)
        return ran

    ran = measure(run, setup=context, rounds=rounds)
    assert sorted(ran) == sorted(DIAG), ran
    benchmark.extra_info["n_points"] = len(cloud)
    benchmark.extra_info["evaluation_stages_s"] = {k: round(ev.timings[k], 4) for k in DIAG + ("total",)}


def test_diagnostics_hammer(measure, benchmark, hammer, hammer_skeleton):
    _diagnostics(benchmark, measure, hammer, *hammer_skeleton, rounds=7)


@pytest.mark.parametrize("n", [100_000])
def test_diagnostics_torus(measure, benchmark, torus, n):
    _diagnostics(benchmark, measure, *torus(n), rounds=3)
