"""Time of the trust additions by cloud size: coverage (skeletal set, curve), reverse projection onto
a skeletal set and onto a curve, the reference comparison. CPU and wall seconds, with the load.

Generated torus (N points), skeletal set = each point's projection onto the core circle + 1% jitter,
curve = a 64-gon of the core circle; the hammer scan against the built-in skeletonizer's output.

    .venv/bin/python benchmarks/bench_trust.py [--sizes 4096 32768]
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
sys.path.insert(0, str(ROOT))

from skelcore import shapes  # noqa: E402
from skelcore.correspondence import densify_curve, project_onto_curve, reverse_projection  # noqa: E402
from skelcore.curve import CurveSkeleton  # noqa: E402
from skelcore.geometry import Normalization  # noqa: E402
from skelcore.metrics.coverage import coverage, coverage_tau  # noqa: E402
from skelcore.metrics.reference import compare_with_reference  # noqa: E402


def timed(fn):
    c, w = time.process_time(), time.perf_counter()
    fn()
    return time.process_time() - c, time.perf_counter() - w


def case(name: str, cloud: np.ndarray, skeletal: np.ndarray, curve: CurveSkeleton) -> None:
    norm = Normalization.from_cloud(cloud)
    c, s, cv = norm.apply(cloud), norm.apply(skeletal), curve.transformed(norm.apply)
    tau = coverage_tau(c)
    pts, _ = densify_curve(cv, tau / 2)
    rows = {
        "skeletal coverage": lambda: coverage(c, s, tau=tau),
        "curve coverage": lambda: coverage(c, np.vstack([pts, cv.vertices]), tau=tau),
        "reverse projection": lambda: reverse_projection(c, s[:: max(1, len(s) // 300)]),
        "curve projection": lambda: project_onto_curve(c, cv),
        "reference (self)": lambda: compare_with_reference(cv, cv, tau),
    }
    for stage, fn in rows.items():
        cpu, wall = timed(fn)
        print(f"| {name} | {len(cloud)} | {stage} | {cpu:.3f} | {wall:.3f} |")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[4096, 32768])
    args = ap.parse_args()
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}")
    print("| shape | N | stage | CPU s | wall s |\n|---|---|---|---|---|")
    for n in args.sizes:
        t = shapes.torus(n, seed=0)
        rng = np.random.default_rng(0)
        skel = t.skeletal + rng.normal(scale=0.01, size=t.skeletal.shape)
        v = np.array([[np.cos(a), np.sin(a), 0.0] for a in np.linspace(0, 2 * np.pi, 64, endpoint=False)])
        curve = CurveSkeleton.from_raw(v, [[i, (i + 1) % 64] for i in range(64)])
        case("torus", t.cloud, skel, curve)
    from skelcore import load_cloud
    from skelcore.skeleton import skeletonize

    cloud = load_cloud(ROOT / "resources" / "scans" / "hammer_4096.ply")
    skel, curve = skeletonize(cloud)
    case("hammer", cloud, skel, curve)
    print(f"load after: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
