"""Every stage but boundedness, by cloud size: time per stage and the longest gap between cancel checks.

The torus of benchmarks/bench_engine.py (R = 1, r = 0.3, N cloud points, skeletal set = each
point's projection onto the core circle + 1 % jitter, curve = a 64-gon, 200 samples) is evaluated
with ``skelcore.evaluate(..., workers=1)`` (the stages one after the other, so that each stage's time,
CPU and gaps are its own; an evaluation runs them side by side); boundedness (timed apart) is replaced, in this benchmark's process only
(unless ``--real-boundedness``), by a function returning 1 for every query (so the trust checks take
their usual "bounded" path) that still calls its checkpoint.  Each size runs in a fresh subprocess
(its own peak memory).  A cancel gap is the time between two consecutive cancel checks; it is charged to the stage
that is running when the gap ends ("a -> b" when it spans the end of a and the start of b: the work
between stages).  CPU s per stage = process time (both threads) from the stage's first progress
report to the next stage's (the work between them included).  ``--trees`` times cKDTree builds.

    .venv/bin/python benchmarks/bench_stages.py [--sizes 65536 262144 1048576] [--trees]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
STAGES = ["topology", "skeletal boundedness", "skeletal centeredness", "skeletal smoothness", "curve boundedness",
          "curve centeredness", "curve smoothness", "skeletal coverage", "curve coverage"]


def run_case(n: int, skip_coverage: bool = False, real_boundedness: bool = False) -> dict:
    import resource

    import numpy as np

    sys.path.insert(0, str(ROOT))
    import importlib

    ev_mod = importlib.import_module("skelcore.stages.catalogue")  # the stages' metric functions
    trust_mod = importlib.import_module("skelcore.stages.assemble")  # the trust checks' boundedness
    from skelcore.stages import evaluate
    from skelcore import Params, shapes

    def cheap_boundedness(cloud, queries, *, params=Params(), checkpoint=lambda f: None):
        checkpoint(1.0)
        return np.ones(len(queries))

    if not real_boundedness:
        ev_mod.boundedness = trust_mod.boundedness = cheap_boundedness
    if skip_coverage:  # --skip-coverage: coverage left out (the stages still run, doing nothing)
        ev_mod.coverage = lambda *a, **k: None
    shape = shapes.torus(n, R=1.0, r=0.3, n_curve=64, seed=0)
    rng = np.random.default_rng(0)
    skeletal = shape.skeletal + rng.normal(scale=0.01, size=shape.skeletal.shape)
    curve = (shape.curve_vertices, shape.curve_edges)

    events: list[list] = []  # [gap, stage label when it ended]
    last = [time.perf_counter()]
    stage = [""]

    starts: list[tuple[str, float]] = []  # (stage, process time when its label first showed)

    def progress(_fraction: float, name: str) -> None:
        if name != stage[0]:
            if events:  # the check just made began this stage: its gap spans both
                events[-1][1] = f"{stage[0] or 'set-up'} -> {name}"
            starts.append((name, time.process_time()))
        stage[0] = name

    def cancel() -> bool:
        now = time.perf_counter()
        events.append([now - last[0], stage[0]])
        last[0] = now
        return False

    cpu0 = time.process_time()
    t0 = time.perf_counter()
    ev = evaluate(shape.cloud, skeletal, curve, Params(), progress=progress, cancel=cancel, workers=1)
    out = {"n": n, "total": time.perf_counter() - t0, "cpu": time.process_time() - cpu0,
           "tail": time.perf_counter() - last[0]}  # after the last check (timings, return)
    out.update({k: v for k, v in ev.timings.items() if k != "total"})
    ends = [t for _, t in starts[1:]] + [time.process_time()]
    out["cpu_stage"] = {name: end - t for (name, t), end in zip(starts, ends)}  # incl. the work after it
    gaps: dict[str, float] = {}
    checks: dict[str, int] = {}
    for gap, key in events:
        gaps[key] = max(gaps.get(key, 0.0), gap)
        checks[key] = checks.get(key, 0) + 1
    out["gaps"], out["checks"] = gaps, checks
    out["peak_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    out["load"] = os.getloadavg()[0]
    return out


def time_trees(n: int) -> dict:
    import threading

    import numpy as np
    from scipy.spatial import cKDTree

    sys.path.insert(0, str(ROOT))
    from skelcore import shapes
    from skelcore.geometry import kd_tree

    cloud = shapes.torus(n, R=1.0, r=0.3, n_curve=64, seed=0).cloud * 0.5
    out = {"n": n, "load": os.getloadavg()[0]}
    for name, build in (("default", lambda: cKDTree(cloud)), ("kd_tree", lambda: kd_tree(cloud))):
        best = np.inf
        for _ in range(3):
            t = time.perf_counter()
            build()
            best = min(best, time.perf_counter() - t)
        out[name] = best
    # does the build release the GIL? count how often a Python thread gets to run during it
    ticks = [0]
    stop = threading.Event()

    def spin() -> None:
        while not stop.is_set():
            ticks[0] += 1
            time.sleep(0.001)

    th = threading.Thread(target=spin)
    th.start()
    t = time.perf_counter()
    kd_tree(cloud)
    dt = time.perf_counter() - t
    stop.set()
    th.join()
    out["ticks_during_build"], out["build_with_thread"] = ticks[0], dt
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="*", default=[65536, 262144, 1048576])
    ap.add_argument("--trees", action="store_true", help="also time cKDTree builds on the cloud")
    ap.add_argument("--skip-coverage", action="store_true", help="leave the two coverage stages out")
    ap.add_argument("--real-boundedness", action="store_true", help="run boundedness too (the table shows it)")
    ap.add_argument("--child", nargs=2, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        n = int(args.child[1])
        print(json.dumps(run_case(n, args.skip_coverage, args.real_boundedness) if args.child[0] == "case"
                         else time_trees(n)))
        return
    print(f"load average at start {os.getloadavg()[0]:.2f}", flush=True)
    for n in args.sizes:
        kinds = ["case"] + (["trees"] if args.trees else [])
        for kind in kinds:
            proc = subprocess.run([sys.executable, __file__, "--child", kind, str(n)]
                                  + (["--skip-coverage"] if args.skip_coverage else [])
                                  + (["--real-boundedness"] if args.real_boundedness else []), capture_output=True, text=True)
            if proc.returncode != 0:
                print(f"{kind} {n}: failed: {proc.stderr.strip().splitlines()[-1:]}", flush=True)
                continue
            r = json.loads(proc.stdout.strip().splitlines()[-1])
            if kind == "trees":
                print(f"  cKDTree build {n}: default {r['default']:.3f} s, kd_tree {r['kd_tree']:.3f} s; a "
                      f"1 ms-sleep thread ran {r['ticks_during_build']} times during a "
                      f"{r['build_with_thread']:.3f} s build (load {r['load']:.2f})", flush=True)
                continue
            stub = "real boundedness" if args.real_boundedness else "boundedness stubbed"
            print(f"\nN = {n}: total {r['total']:.2f} s ({stub}), CPU {r['cpu']:.2f} s, "
                  f"peak {r['peak_mb']:.0f} MB, load at end {r['load']:.2f}")
            print("| stage | wall s | CPU s | checks | longest cancel gap s |\n|---|---|---|---|---|")
            for s in STAGES:
                if s in r:
                    print(f"| {s} | {r[s]:.3f} | {r.get('cpu_stage', {}).get(s, float('nan')):.2f} | "
                          f"{r['checks'].get(s, 0)} | {r['gaps'].get(s, 0.0):.3f} |")
            for k, v in sorted(r["gaps"].items(), key=lambda kv: -kv[1]):
                if k not in STAGES and v > 0.05:
                    print(f"| (gap) {k or 'before the first stage'} | | | {v:.3f} |")
            print(f"| after the last check | | | {r['tail']:.3f} |", flush=True)
    print(f"\nload average at end {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
