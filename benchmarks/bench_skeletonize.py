"""Time of skelcore.skeletonize (rings + contraction + curve) for both methods, by cloud size.

Cases: the paper's hammer (4096) and apple tree (grid 0.02, 8936) of resources/scans (unless --no-real),
then the closed cylinder and the Y shape at each size. Reports the contraction iterations, the
split between contraction and curve extraction, the curve's size, and the worst cancel latency
seen when a cancel is raised mid-solve (``--cancel``). One run per case; quote ``uptime`` with it.

    .venv/bin/python benchmarks/bench_skeletonize.py [--sizes 4096 16384 65536] [--methods cao skelscope]
        [--shapes cylinder y_shape] [--solver auto|cholmod|superlu] [--cancel S ...] [--no-real]
"""

from __future__ import annotations

import argparse
import os
import threading
import time
from pathlib import Path

from skelcore.errors import Cancelled
from skelcore.shapes import cylinder, y_shape
from skelcore.skeleton import skeletonize

SCANS = Path(__file__).resolve().parents[1] / "resources" / "scans"


def _cases(sizes: list[int], real: bool, names: list[str]):
    if real:
        from skelcore.io import load_cloud
        from skelcore.skeleton.degrade import voxel_grid_average

        yield "hammer", load_cloud(SCANS / "hammer_4096.ply")
        yield "tree", voxel_grid_average(load_cloud(SCANS / "apple_tree_22367.ply"), 0.02)[0]
    makers = {"cylinder": cylinder, "y_shape": y_shape}
    for n in sizes:
        for name in names:
            yield name, makers[name](n).cloud


def _params(method: str, solver: str | None):
    """The method's default parameters, with ``linear_solver`` set when asked for."""
    if solver is None:
        return None
    from skelcore.skeleton import CaoParams, SkeletonizeParams

    return (CaoParams if method == "cao" else SkeletonizeParams)(linear_solver=solver)


def _cancel_latency(cloud, method: str, after: float, solver: str | None = None) -> float:
    """Raise the cancel flag ``after`` seconds into a run; seconds until Cancelled came back."""
    flag = threading.Event()
    raised = {}

    def later() -> None:
        time.sleep(after)
        raised["t"] = time.perf_counter()
        flag.set()

    threading.Thread(target=later, daemon=True).start()
    try:
        skeletonize(cloud, _params(method, solver), method=method, cancel=flag.is_set)
    except Cancelled:
        return time.perf_counter() - raised["t"]
    return float("nan")  # finished before the cancel


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[4096, 16384, 65536])
    ap.add_argument("--methods", nargs="+", default=["cao", "skelscope"])
    ap.add_argument("--no-real", action="store_true", help="skip the real scans (resources/scans)")
    ap.add_argument("--shapes", nargs="+", default=["cylinder", "y_shape"], choices=["cylinder", "y_shape"])
    ap.add_argument("--solver", default=None, choices=["auto", "cholmod", "superlu"],
                    help="linear_solver of the method's parameters (default: the library's default)")
    ap.add_argument("--cancel", type=float, nargs="*", default=None, metavar="S",
                    help="also measure cancel latency, raising the flag S seconds into each run")
    args = ap.parse_args()
    print(f"load average {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f}")
    print(f"{'case':8} {'N':>7} {'method':9} {'iters':>5} {'contract s':>10} {'curve s':>8} {'total s':>8} "
          f"{'CPU s':>7} {'V':>5} {'E':>5}")
    for name, cloud in _cases(args.sizes, not args.no_real, args.shapes):
        for method in args.methods:
            cpu = time.process_time()
            _sk, curve, info = skeletonize(cloud, _params(method, args.solver), method=method, return_info=True)
            cpu = time.process_time() - cpu
            t = info.timings
            print(f"{name:8} {len(cloud):7d} {method:9} {info.iterations:5d} {t['contraction']:10.2f} "
                  f"{t['curve']:8.2f} {t['total']:8.2f} {cpu:7.2f} {curve.n_vertices:5d} {curve.n_edges:5d}", flush=True)
            for after in args.cancel or []:
                lat = _cancel_latency(cloud, method, after, args.solver)
                print(f"{'':8} {'':7} {method:9} cancel at {after:.1f} s: back after {lat:.3f} s", flush=True)
    print(f"load average {os.getloadavg()[0]:.2f} {os.getloadavg()[1]:.2f}")


if __name__ == "__main__":
    main()
