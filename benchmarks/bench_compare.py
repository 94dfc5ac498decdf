"""Wall time and scheduler overhead of ``skelcore compare`` on each backend.

12 generated shapes (4 cylinders, 4 tori, 4 Y shapes; --points each) x 2 methods (the built-in
skeletonizer and an external command drawing the principal axis) x 3 conditions (normal, 5% noise,
--points/4 random points), run serially, on a process pool of 2 and on a Dask LocalCluster of 2,
each into a fresh folder (no job is skipped).

Per-job overhead = the idle gap on a worker between the end of one job and the start of its next
(dispatch, pickling, result transfer, the driver filing the record), from the timestamps each job
records; shown as a share of the mean job time. Startup = run start to the first job's start.

    .venv/bin/python benchmarks/bench_compare.py [--points 4096] [--backends serial pool dask]
"""

from __future__ import annotations

import argparse
import os
import shlex
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from skelcore import shapes
from skelcore.compare import Backend, run_compare
from skelcore.io import write_points_ply

LINE = """
import sys, numpy as np
from skelcore.io import load_cloud, write_curve_ply
c = load_cloud(sys.argv[1]); m = c.mean(axis=0); u = np.linalg.svd(c - m, full_matrices=False)[2][0]
t = (c - m) @ u; v = m + np.outer(np.linspace(t.min(), t.max(), 16), u)
write_curve_ply(sys.argv[2], v, np.column_stack([np.arange(15), np.arange(1, 16)]))
"""


def make_dataset(root: Path, n: int) -> Path:
    (root / "clouds").mkdir(parents=True)
    k = 0
    for i in range(4):
        for name, shape in (("cylinder", shapes.cylinder(n, radius=0.4 + 0.1 * i, seed=i)),
                            ("torus", shapes.torus(n, r=0.2 + 0.05 * i, seed=i)),
                            ("yshape", shapes.y_shape(n, arm=1.5 + 0.25 * i, seed=i))):
            write_points_ply(root / "clouds" / f"{name}{i}.ply", shape.cloud)
            k += 1
    (root / "line.py").write_text(LINE)
    cmd = f"{shlex.quote(sys.executable)} line.py {{in}} {{out_curve}}"
    (root / "m.toml").write_text(f"""
[[shapes]]
path = "clouds/*.ply"
[[methods]]
name = "builtin"
kind = "builtin"
[[methods]]
name = "axis"
kind = "command"
command = "{cmd}"
[[conditions]]
name = "normal"
[[conditions]]
name = "noise"
noise = 0.05
[[conditions]]
name = "sparse"
sparse = {n // 4}
""")
    return root / "m.toml"


def overhead(records: list[dict], t_start: float) -> tuple[float, float, float]:
    """(mean idle gap between consecutive jobs on a worker, mean job seconds, startup seconds)."""
    by_pid: dict[int, list[dict]] = {}
    for r in records:
        by_pid.setdefault(r["pid"], []).append(r)
    gaps = []
    for recs in by_pid.values():
        recs.sort(key=lambda r: r["started"])
        gaps += [b["started"] - a["finished"] for a, b in zip(recs, recs[1:])]
    first = min(r["started"] for r in records)
    return float(np.mean(gaps)) if gaps else 0.0, float(np.mean([r["seconds"] for r in records])), first - t_start


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=4096)
    ap.add_argument("--backends", nargs="+", default=["serial", "pool", "dask"], choices=["serial", "pool", "dask"])
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    backends = {"serial": Backend("serial"), "pool": Backend("pool", args.workers), "dask": Backend("dask", args.workers)}
    with tempfile.TemporaryDirectory(prefix="bench-compare-") as tmp:
        manifest = make_dataset(Path(tmp), args.points)
        print(f"{args.points}-point shapes, 12 x 2 methods x 3 conditions = 72 jobs; "
              f"load average before: {' '.join(f'{x:.2f}' for x in os.getloadavg())}", flush=True)
        print("| backend | wall s | sum of job s | mean job s | per-job overhead | share of job | startup s | load after |")
        print("|---|---|---|---|---|---|---|---|")
        for name in args.backends:
            t_wall = time.time()
            t0 = time.perf_counter()
            res = run_compare(manifest, Path(tmp) / f"out_{name}", backends[name], report=False)
            wall = time.perf_counter() - t0
            recs = [r for r in res.summary.records if "started" in r]
            gap, mean_job, startup = overhead(recs, t_wall)
            total = sum(r["seconds"] for r in recs)
            print(f"| {backends[name].describe()} | {wall:.1f} | {total:.1f} | {mean_job:.2f} | {gap * 1000:.0f} ms | "
                  f"{100 * gap / mean_job:.2f}% | {startup:.2f} | {os.getloadavg()[0]:.2f} |", flush=True)
            assert res.summary.ok == 72, [r["error"] for r in res.summary.records if r["status"] != "ok"][:3]


if __name__ == "__main__":
    main()
