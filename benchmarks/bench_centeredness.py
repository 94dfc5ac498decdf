"""Time of skeletal and curve centeredness (docs/metrics.md 3) by cloud size, in normalized space.

Shapes: a closed cylinder (skeletal set = projections onto the axis, curve = the axis shifted by
0.2 r) and the Y shape (three arms, one joint). Curve: 200 samples. Best of ``--repeat`` runs.

    .venv/bin/python benchmarks/bench_centeredness.py [--sizes 4096 65536 262144] [--repeat 3]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from skelcore.curve import CurveSkeleton
from skelcore.metrics.curve_sampling import sample_curve
from skelcore.geometry import Normalization
from skelcore.metrics.centeredness import curve_centeredness, skeletal_centeredness
from skelcore.shapes import cylinder, y_shape


def _best(fn, repeat: int) -> float:
    best = np.inf
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[4096, 65536, 262144])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    print(f"{'shape':8} {'N':>8} {'skeletal s':>11} {'curve 200 s':>12} {'curve samples':>14}")
    for n in args.sizes:
        for name, shape in (("cylinder", cylinder(n, radius=0.5)), ("y_shape", y_shape(n))):
            norm = Normalization.from_cloud(shape.cloud)
            cloud, skel = norm.apply(shape.cloud), norm.apply(shape.skeletal)
            verts = shape.curve_vertices + (np.array([0.1, 0.0, 0.0]) if name == "cylinder" else 0.0)
            samples = sample_curve(CurveSkeleton.from_raw(norm.apply(verts), shape.curve_edges), 200)
            t_skel = _best(lambda: skeletal_centeredness(cloud, skel), args.repeat)
            t_curve = _best(lambda: curve_centeredness(cloud, samples.points, samples.directions), args.repeat)
            print(f"{name:8} {len(cloud):8d} {t_skel:11.3f} {t_curve:12.3f} {len(samples):14d}")


if __name__ == "__main__":
    main()
