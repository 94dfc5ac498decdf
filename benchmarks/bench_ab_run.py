"""What keeping each job's whole Evaluation costs ``skelcore compare``, and how fast the viewer gets
two report rows back.

One torus of --points points, two ``files`` methods (its true skeleton and a jittered copy, skeletal
set and curve), condition normal, run serially into a fresh folder. Reports per job: the npz size
with and without the ``ev_`` arrays (the latter re-compressed here), the time to write it, and the
time of ``open_run`` + both stored Evaluations (``app.compare_run.load_ab``'s engine part, no Qt).

    .venv/bin/python benchmarks/bench_ab_run.py [--points 30000] [--repeat 5]
"""

from __future__ import annotations

import argparse
import io
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from skelcore import shapes
from skelcore.compare import Backend, run_compare
from skelcore.compare.finished_run import open_run
from skelcore.io import write_curve_ply, write_points_ply

MANIFEST = """
[[shapes]]
path = "torus.ply"
[[methods]]
name = "truth"
kind = "files"
skeletal = "{stem}_truth_skeletal.ply"
curve = "{stem}_truth_curve.ply"
[[methods]]
name = "jitter"
kind = "files"
skeletal = "{stem}_jitter_skeletal.ply"
curve = "{stem}_jitter_curve.ply"
[[conditions]]
name = "normal"
"""


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--points", type=int, default=30000)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    root = Path(tempfile.mkdtemp(prefix="bench-ab-run-"))
    t = shapes.torus(args.points, seed=0)
    rng = np.random.default_rng(1)
    write_points_ply(root / "torus.ply", t.cloud)
    write_points_ply(root / "torus_truth_skeletal.ply", t.skeletal)
    write_curve_ply(root / "torus_truth_curve.ply", t.curve_vertices, t.curve_edges)
    write_points_ply(root / "torus_jitter_skeletal.ply", t.skeletal + rng.normal(0, 0.03, t.skeletal.shape))
    write_curve_ply(root / "torus_jitter_curve.ply", t.curve_vertices + rng.normal(0, 0.03, t.curve_vertices.shape),
                    t.curve_edges)
    (root / "m.toml").write_text(MANIFEST)
    t0 = time.perf_counter()
    run_compare(root / "m.toml", root / "out", Backend("serial"), report=False)
    print(f"run (2 jobs, {args.points} points): {time.perf_counter() - t0:.1f} s; load {os.getloadavg()[0]:.1f}")
    for npz in sorted((root / "out" / "jobs").glob("*.npz")):
        with np.load(npz) as z:
            arrays = {k: z[k] for k in z.files}
        report_only = {k: v for k, v in arrays.items() if not k.startswith("ev_")}
        buf = io.BytesIO()
        t0 = time.perf_counter()
        np.savez_compressed(buf, **arrays)
        write_all = time.perf_counter() - t0
        small = io.BytesIO()
        t0 = time.perf_counter()
        np.savez_compressed(small, **report_only)
        write_report = time.perf_counter() - t0
        print(f"{npz.name}: {len(small.getvalue()) / 1e3:.0f} kB -> {npz.stat().st_size / 1e3:.0f} kB "
              f"(x {npz.stat().st_size / len(small.getvalue()):.2f}); compress {write_report * 1e3:.0f} -> "
              f"{write_all * 1e3:.0f} ms")
    times = []
    for _ in range(args.repeat):
        t0 = time.perf_counter()
        run = open_run(root / "out")
        for method in ("truth", "jitter"):
            run.evaluation(run.find("torus", method))
        times.append(time.perf_counter() - t0)
    print(f"open_run + two stored Evaluations: median {np.median(times) * 1e3:.0f} ms, min {min(times) * 1e3:.0f} ms "
          f"over {args.repeat}; load {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
