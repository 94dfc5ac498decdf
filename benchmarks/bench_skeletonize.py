"""The built-in skeletonizer (``skelcore.skeletonize``: rings, contraction, curve) with both methods:
the hammer scan and the closed cylinder of 16,384 points (docs/skeletonize.md). Each case's
iterations, its split between contraction and curve, and the curve's size are in its extra_info."""

from __future__ import annotations

import pytest

from skelcore.skeleton import skeletonize

METHODS = ["cao", "skelscope"]


def _skeletonize(benchmark, measure, cloud, method: str, rounds: int, warmup: int = 1) -> None:
    _sk, curve, info = measure(lambda: skeletonize(cloud, method=method, return_info=True), rounds=rounds,
                                 warmup=warmup)
    benchmark.extra_info.update(
        n_points=len(cloud), iterations=int(info.iterations),
        timings_s={k: round(v, 4) for k, v in info.timings.items()},
        curve_vertices=int(curve.n_vertices), curve_edges=int(curve.n_edges),
    )


@pytest.mark.parametrize("method", METHODS)
def test_skeletonize_hammer(measure, benchmark, hammer, method):
    _skeletonize(benchmark, measure, hammer, method, rounds=5)


@pytest.mark.parametrize("method", METHODS)
def test_skeletonize_cylinder_16384(measure, benchmark, method):
    from skelcore.shapes import cylinder

    _skeletonize(benchmark, measure, cylinder(16_384).cloud, method, rounds=3, warmup=0)
