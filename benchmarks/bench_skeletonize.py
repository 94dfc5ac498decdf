"""The built-in skeletonizer (``skelcore.skeletonize``: rings, contraction, curve) with both methods:
the hammer scan and the closed cylinder of 16,384 points (docs/skeletonize.md); the default pipeline
on a thin Y, its axis curve by rings and by balls. Each case's iterations, its split between
contraction and curve, and the curve's size are in its extra_info."""

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


@pytest.mark.parametrize("curve", ["rings", "balls"])
def test_default_thin_y_12000(measure, benchmark, curve):
    """The default pipeline on a Y of radius 0.01 (12,000 points): the moves and the axis curve by
    rings or by balls (docs/skeletonize.md "Thin parts")."""
    from skelcore.shapes import y_shape
    from skelcore.skeleton.default import default_skeleton
    from skelcore.skeleton.skeleton_params import AxisParams

    cloud = y_shape(12_000, radius=0.01, seed=5).cloud
    _sk, c, info, choice = measure(lambda: default_skeleton(cloud, axis=AxisParams(curve=curve)), rounds=3, warmup=0)
    benchmark.extra_info.update(n_points=len(cloud), method=choice.method, curve_vertices=int(c.n_vertices),
                                timings_s={k: round(v, 4) for k, v in info.timings.items()})
