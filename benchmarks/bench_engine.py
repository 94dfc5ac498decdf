"""Full evaluations (``skelcore.evaluate``, every stage, the stages side by side as a user gets them):
the hammer scan against the built-in skeletonizer's output, and the reference torus at 100k and 1M
points (whole, curve only, and with coverage raised above the cloud's size so that coverage and the
diagnostics run at 1M). Each case's per-stage seconds of its last round are in its extra_info.
Timed in this process after one untimed call (the first call's imports and kernel loading aside)."""

from __future__ import annotations

import pytest

from skelcore import Params, evaluate

#: the diagnostics' stages (their seconds summed into extra_info["diagnostics_s"])
DIAG = ("curve defects", "skeletal missing parts", "curve missing parts")


def _with_peak(benchmark, peak_rss_mb, call: str, curve_only: bool = False) -> None:
    """The peak resident memory (``peak_rss_mb`` in extra_info) of a fresh process that makes the
    torus and runs ``call`` on it (``cloud``, ``skeletal``, ``curve``, ``n``, ``Params``, ``evaluate``
    in scope), imports and inputs included."""
    setup = ("from conftest import _torus\nfrom skelcore import Params, evaluate\nn = 1_048_576\n"
             f"cloud, skeletal, curve = _torus(n, curve_only={curve_only})\n")
    benchmark.extra_info["peak_rss_mb"] = peak_rss_mb(setup + call)


def _record(benchmark, ev, n_points: int) -> None:
    timings = {k: round(v, 4) for k, v in ev.timings.items()}
    benchmark.extra_info["n_points"] = n_points
    benchmark.extra_info["stages_s"] = timings
    benchmark.extra_info["diagnostics_s"] = round(sum(timings.get(k, 0.0) for k in DIAG), 4)
    covs = [c for c in (ev.coverage_skeletal, ev.coverage_curve) if c is not None]
    benchmark.extra_info["coverage_subsample"] = next((c.subsample for c in covs if c.subsample), None)


def test_evaluate_hammer(measure, benchmark, hammer, hammer_skeleton):
    skeletal, curve = hammer_skeleton
    ev = measure(lambda: evaluate(hammer, skeletal, curve), rounds=7)
    _record(benchmark, ev, len(hammer))


@pytest.mark.parametrize("n", [100_000, pytest.param(1_048_576, marks=pytest.mark.large)])
def test_evaluate_torus(measure, benchmark, torus, n, peak_rss_mb):
    cloud, skeletal, curve = torus(n)
    ev = measure(lambda: evaluate(cloud, skeletal, curve), rounds=3, warmup=1 if n < 1_000_000 else 0)
    if n >= 1_000_000:
        _with_peak(benchmark, peak_rss_mb, "evaluate(cloud, skeletal, curve)")
    _record(benchmark, ev, n)


@pytest.mark.large
def test_evaluate_torus_curve_only_1m(measure, benchmark, torus, peak_rss_mb):
    n = 1_048_576
    cloud, _skeletal, curve = torus(n, curve_only=True)
    ev = measure(lambda: evaluate(cloud, None, curve), rounds=3, warmup=1)
    _with_peak(benchmark, peak_rss_mb, "evaluate(cloud, None, curve)", curve_only=True)
    _record(benchmark, ev, n)


@pytest.mark.large
def test_evaluate_torus_coverage_and_diagnostics_1m(measure, benchmark, torus, peak_rss_mb):
    """coverage_max_points raised above N (above coverage_exact_points coverage is estimated on a
    subsample), so that coverage and the diagnostics that read it run at 1M."""
    n = 1_048_576
    cloud, skeletal, curve = torus(n)
    params = Params(coverage_max_points=n + 1)
    ev = measure(lambda: evaluate(cloud, skeletal, curve, params), rounds=3, warmup=0)
    _with_peak(benchmark, peak_rss_mb, "evaluate(cloud, skeletal, curve, Params(coverage_max_points=n + 1))")
    _record(benchmark, ev, n)
