"""Coverage alone (docs/metrics.md 5.2): skeletal and curve coverage of the hammer and apple
tree scans (built-in skeletonizer, cached in /tmp) and of bench_engine.py's torus by size, wall and CPU s,
the worst gap between two checkpoints, with the load average.

Torus: R = 1, r = 0.3, N points; skeletal set = each point's projection onto the core circle + 1 %
jitter; curve = a 64-gon of the core circle, densified as the evaluation does.  tau is computed
apart (``coverage_tau``, timed on its own row).  Each case runs in this process, one after another.

    .venv/bin/python benchmarks/bench_coverage.py [--sizes 16384 65536] [--no-real]
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SCANS = ROOT / "resources" / "scans"
sys.path.insert(0, str(ROOT))

from skelcore import shapes  # noqa: E402
from skelcore.correspondence import densify_curve  # noqa: E402
from skelcore.curve import CurveSkeleton  # noqa: E402
from skelcore.geometry import Normalization  # noqa: E402
from skelcore.metrics.coverage import coverage, coverage_tau  # noqa: E402
from skelcore.params import Params  # noqa: E402


def _scan(path: Path) -> tuple[np.ndarray, np.ndarray, CurveSkeleton]:
    from skelcore.io import load_cloud
    from skelcore.skeleton.pipeline import skeletonize

    cloud = load_cloud(str(path))
    cache = Path("/tmp") / f"skelscope_bench_coverage_{path.stem}.npz"
    if cache.is_file():
        z = np.load(cache)
        return cloud, z["skeletal"], CurveSkeleton(z["vertices"], z["edges"])
    skeletal, curve = skeletonize(cloud)
    np.savez(cache, skeletal=skeletal, vertices=curve.vertices, edges=curve.edges)
    return cloud, skeletal, curve


def _torus(n: int) -> tuple[np.ndarray, np.ndarray, CurveSkeleton]:
    shape = shapes.torus(n, R=1.0, r=0.3, n_curve=64, seed=0)
    skeletal = shape.skeletal + np.random.default_rng(0).normal(scale=0.01, size=shape.skeletal.shape)
    return shape.cloud, skeletal, CurveSkeleton(shape.curve_vertices, shape.curve_edges)


def _timed(fn):
    gaps = [0.0]
    last = [time.perf_counter()]

    def check(_f: float) -> None:
        now = time.perf_counter()
        gaps[0] = max(gaps[0], now - last[0])
        last[0] = now

    c, w = time.process_time(), time.perf_counter()
    out = fn(check)
    gaps[0] = max(gaps[0], time.perf_counter() - last[0])
    return out, time.process_time() - c, time.perf_counter() - w, gaps[0]


def case(name: str, cloud: np.ndarray, skeletal: np.ndarray, curve: CurveSkeleton) -> None:
    p = Params()
    norm = Normalization.from_cloud(cloud, p.normalize_by, p.normalized_size)
    c, s, cv = norm.apply(cloud), norm.apply(skeletal), curve.transformed(norm.apply)
    tau, cpu, wall, gap = _timed(lambda ck: coverage_tau(c, p, ck))
    print(f"| {name} | {len(c)} | tau | {wall:.3f} | {cpu:.3f} | {gap:.3f} | | |", flush=True)
    step = max(tau / p.coverage_tau_factor, float(cv.edge_lengths().sum()) / 200_000)
    pts, _ = densify_curve(cv, step)
    for kind, elements in (("skeletal", s), ("curve", np.vstack([pts, cv.vertices]))):
        cov, cpu, wall, gap = _timed(lambda ck: coverage(c, elements, p, tau, checkpoint=ck))
        print(f"| {name} | {len(c)} | {kind} ({cov.n_elements} elements) | {wall:.3f} | {cpu:.3f} | {gap:.3f} "
              f"| {cov.fraction:.4f} | {cov.mean_gap:.3e} / {cov.max_gap:.3e} |", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="*", default=[16384, 65536, 262144, 1048576])
    ap.add_argument("--no-real", action="store_true", help="skip the real scans (resources/scans)")
    args = ap.parse_args()
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"load average at start {os.getloadavg()[0]:.2f}")
    print("| shape | N | stage | wall s | CPU s | worst check gap s | fraction | mean / max gap |")
    print("|---|---|---|---|---|---|---|---|", flush=True)
    if not args.no_real:
        for stem in ("hammer_4096", "apple_tree_22367"):
            case(stem, *_scan(SCANS / f"{stem}.ply"))
    for n in args.sizes:
        case(f"torus {n}", *_torus(n))
    print(f"load average at end {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
