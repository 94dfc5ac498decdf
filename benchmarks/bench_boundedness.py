"""Boundedness (docs/metrics.md 2) speed and accuracy by cloud size.

Shapes as in bench_engine.py: a torus (R = 1, r = 0.3) sampled with N points; queries = its skeletal
set (each point projected onto the core circle, 1 % jitter) + 200 curve samples, normalized (docs/metrics.md 0).
For every size: wall and CPU time of ``boundedness_rays`` with the default parameters, and its error
against every-pair evaluation on a random subset of queries (the shared far field is the only
approximation beyond the raster).  ``--brute`` also checks every-pair evaluation against a 200k
direction brute force on small clouds; ``--paper`` times the paper estimator on a query subset.

    .venv/bin/python benchmarks/bench_boundedness.py [--sizes 4096 16384 65536] [--brute] [--paper]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from skelcore.geometry import Normalization  # noqa: E402
from skelcore.metrics.boundedness import boundedness_paper, boundedness_rays, rays_radius  # noqa: E402
from skelcore.shapes import cylinder, sphere_surface, torus  # noqa: E402


def torus_case(n: int) -> tuple[np.ndarray, np.ndarray]:
    shape = torus(n, 1.0, 0.3, n_curve=64, seed=0)
    rng = np.random.default_rng(0)
    skeletal = shape.skeletal + rng.normal(scale=0.01, size=shape.skeletal.shape)
    a = rng.uniform(0, 2 * np.pi, 200)
    samples = np.column_stack([np.cos(a), np.sin(a), np.zeros(200)])
    norm = Normalization.from_cloud(shape.cloud)
    return norm.apply(shape.cloud), norm.apply(np.vstack([skeletal, samples]))


def timed(fn, *args, **kwargs):
    w, c = time.perf_counter(), time.process_time()
    out = fn(*args, **kwargs)
    return out, time.perf_counter() - w, time.process_time() - c


def brute(cloud: np.ndarray, queries: np.ndarray, n_dirs: int = 200_000) -> np.ndarray:
    from scipy.spatial import cKDTree

    i = np.arange(n_dirs) + 0.5
    z = 1 - 2 * i / n_dirs
    phi = np.pi * (1 + 5**0.5) * i
    r = np.sqrt(1 - z * z)
    tree = cKDTree(np.column_stack([r * np.cos(phi), r * np.sin(phi), z]))
    h = rays_radius(cloud)
    out = []
    for q in queries:
        d = cloud - q
        dist = np.linalg.norm(d, axis=1)
        far = dist > h
        covered = np.zeros(n_dirs, bool)
        for hits in tree.query_ball_point(d[far] / dist[far, None], 2 * np.sin(np.arcsin(h / dist[far]) / 2)):
            covered[hits] = True
        out.append(covered.mean())
    return np.array(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="*", default=[4096, 16384, 65536])
    ap.add_argument("--check", type=int, default=200, help="queries compared with every-pair evaluation")
    ap.add_argument("--brute", action="store_true")
    ap.add_argument("--paper", action="store_true")
    ap.add_argument("--workers", type=int, default=None, help="threads (default: the estimator's choice)")
    args = ap.parse_args()
    rng = np.random.default_rng(1)
    print("rays: N, queries, wall s, CPU s, max |error| / mean error vs every pair on a subset")
    for n in args.sizes:
        cloud, queries = torus_case(n)
        beta, wall, cpu = timed(boundedness_rays, cloud, queries, workers=args.workers)
        pick = rng.choice(len(queries), min(args.check, len(queries)), replace=False)
        exact = boundedness_rays(cloud, queries[pick], share_far_field=False)
        err = beta[pick] - exact
        print(f"  {n:7d} {len(queries):7d} {wall:7.2f} {cpu:7.2f}   {np.abs(err).max():.4f} / {err.mean():+.5f}")
    if args.brute:
        print("every pair vs 200k-direction brute force: max |error|")
        cases = {
            "sphere 1000, in/out/near": (sphere_surface(1000, 0.8, seed=1), [[0, 0, 0], [1.6, 0, 0], [0.79, 0, 0]]),
            "torus 1500, hole/tube": (torus(1500, 0.8, 0.24, seed=2).cloud, [[0, 0, 0], [0.8, 0, 0]]),
            "open cylinder 1200": (cylinder(1200, 0.4, 1.6, capped=False, seed=3).cloud, [[0, 0, 0.8], [0, 0, 2.0]]),
        }
        for name, (cloud, q) in cases.items():
            q = np.array(q, float)
            got = boundedness_rays(cloud, q, share_far_field=False)
            print(f"  {name:28s} {np.abs(got - brute(cloud, q)).max():.4f}")
    if args.paper:
        cloud, queries = torus_case(4096)
        sub = queries[rng.choice(len(queries), 200, replace=False)]
        _, wall, cpu = timed(boundedness_paper, cloud, sub)
        scale = len(queries) / len(sub)
        print(f"paper, 4096 points: {wall:.2f} s wall / {cpu:.2f} s CPU for 200 queries, "
              f"so about {wall * scale:.0f} s wall for all {len(queries)}")


if __name__ == "__main__":
    main()
