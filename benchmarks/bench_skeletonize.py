"""Time of skelcore.skeletonize (contraction + curve) by cloud size.

Shapes: the closed cylinder and the Y shape at each size. Reports the contraction iterations, the
split between contraction and curve extraction, and the curve's size. One run per size (the
contraction dominates and does not vary between runs).

    .venv/bin/python benchmarks/bench_skeletonize.py [--sizes 4096 16384 65536]
"""

from __future__ import annotations

import argparse

from skelcore.shapes import cylinder, y_shape
from skelcore.skeleton import skeletonize


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[4096, 16384, 65536])
    args = ap.parse_args()
    print(f"{'shape':8} {'N':>7} {'iters':>5} {'contract s':>10} {'curve s':>8} {'total s':>8} {'V':>5} {'E':>5}")
    for n in args.sizes:
        for name, shape in (("cylinder", cylinder(n)), ("y_shape", y_shape(n))):
            _sk, curve, info = skeletonize(shape.cloud, return_info=True)
            t = info.timings
            print(f"{name:8} {n:7d} {info.iterations:5d} {t['contraction']:10.2f} {t['curve']:8.2f} "
                  f"{t['total']:8.2f} {curve.n_vertices:5d} {curve.n_edges:5d}", flush=True)


if __name__ == "__main__":
    main()
