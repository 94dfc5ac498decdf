"""Per-metric time and peak memory of a full evaluation (skeletal points + curve) by cloud size.

Each case runs in a fresh subprocess so its peak resident memory (ru_maxrss) is its own.
Generated shapes: a torus sampled with N points, its skeletal set = each point's projection onto the
core circle plus 1% jitter, its curve = a 64-gon of the core circle. Real clouds from
../shared/data/ are scored against the built-in skeletonizer's output when it is available.

    .venv/bin/python benchmarks/bench_engine.py [--sizes 4096 16384 65536 262144] [--markdown]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "data"
STAGES = [
    "topology",
    "skeletal boundedness",
    "skeletal centeredness",
    "skeletal smoothness",
    "curve boundedness",
    "curve centeredness",
    "curve smoothness",
]


def run_case(kind: str, arg: str, method: str) -> dict:
    import resource

    import numpy as np

    sys.path.insert(0, str(ROOT))
    from skelcore import Params, evaluate, shapes

    out: dict = {"case": arg}
    if kind == "torus":
        n = int(arg)
        shape = shapes.torus(n, R=1.0, r=0.3, n_curve=64, seed=0)
        rng = np.random.default_rng(0)
        cloud = shape.cloud
        skeletal = shape.skeletal + rng.normal(scale=0.01, size=shape.skeletal.shape)
        curve = (shape.curve_vertices, shape.curve_edges)
        out["case"] = f"torus {n}"
    else:
        from skelcore.io import load_cloud
        from skelcore.skeleton import skeletonize

        cloud = load_cloud(arg)
        t0 = time.perf_counter()
        skeletal, curve = skeletonize(cloud)
        out["skeletonize"] = time.perf_counter() - t0
        out["case"] = Path(arg).stem
    out["n_points"] = int(len(cloud))
    ev = evaluate(cloud, skeletal, curve, Params(boundedness_method=method))
    out.update(ev.timings)
    out["peak_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    return out


def _cpu_model() -> str:
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="*", default=[4096, 16384, 65536, 262144])
    ap.add_argument("--method", default="rays", choices=("rays", "paper"))
    ap.add_argument("--no-real", action="store_true", help="skip ../shared/data clouds")
    ap.add_argument("--child", nargs=2, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        print(json.dumps(run_case(args.child[0], args.child[1], args.method)))
        return
    cases = [("torus", str(n)) for n in args.sizes]
    if not args.no_real and SHARED.is_dir():
        cases += [("real", str(p)) for p in sorted(SHARED.glob("*.ply"))]
    print(f"machine: {_cpu_model()}, {os.cpu_count()} cores, Python {platform.python_version()}, load average {os.getloadavg()[0]:.1f}")
    head = ["case", "points"] + [s.replace("skeletal ", "skel ") for s in STAGES] + ["total s", "peak MB"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    for kind, arg in cases:
        proc = subprocess.run(
            [sys.executable, __file__, "--method", args.method, "--child", kind, arg],
            capture_output=True, text=True,
        )
        if proc.returncode != 0:
            print(f"| {arg} | failed: {proc.stderr.strip().splitlines()[-1] if proc.stderr.strip() else proc.returncode} |")
            continue
        r = json.loads(proc.stdout.strip().splitlines()[-1])
        cells = [r["case"], str(r["n_points"])] + [f"{r.get(s, float('nan')):.3f}" for s in STAGES]
        cells += [f"{r['total']:.2f}", f"{r['peak_mb']:.0f}"]
        if "skeletonize" in r:
            cells[0] += f" (skeletonize {r['skeletonize']:.1f} s)"
        print("| " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
