"""Engine speed against the targets of issue 12: full evaluations by size, real scans, cancel latency.

Every case runs in a fresh subprocess, so its time includes the fresh process's first call
("start-up" = interpreter + imports, reported separately) and its peak resident memory (ru_maxrss) is its own; CPU s = process time of
all threads (the fairer figure when other jobs share the cores).  Generated shapes: a torus
(R = 1, r = 0.3) sampled with N points, skeletal set = each point's projection onto the core circle
+ 1 % jitter, curve = a 64-gon of the core circle.  Real clouds from ../shared/data/ are scored
against the built-in skeletonizer's output (its time reported apart).  The yardstick: gudhi's
Vietoris-Rips H0 of the hammer scan, timed in the same run.  The worst cancel latency is the longest
gap between two cancel checks of a run (the cancel callback times itself).

    .venv/bin/python benchmarks/bench_engine.py                 # the issue-12 target table
    .venv/bin/python benchmarks/bench_engine.py --sizes 4096 16384 --no-real --no-targets   # by size
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import threading
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
    "skeletal coverage",
    "curve coverage",
]


def run_case(kind: str, arg: str, method: str) -> dict:
    import resource

    t_start = time.perf_counter()
    import numpy as np

    sys.path.insert(0, str(ROOT))
    from skelcore import Params, evaluate, shapes

    out: dict = {"case": arg, "startup": time.perf_counter() - t_start}
    if kind == "rips":
        import gudhi

        from skelcore.io import load_cloud

        cloud = load_cloud(arg)
        t0, cpu0 = time.perf_counter(), time.process_time()
        st = gudhi.RipsComplex(points=cloud).create_simplex_tree(max_dimension=1)
        st.persistence()
        out.update(case=f"gudhi Rips H0, {Path(arg).stem}", n_points=len(cloud), total=time.perf_counter() - t0,
                   cpu=time.process_time() - cpu0)
        out["peak_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
        return out
    curve_only = kind == "torus-curve"
    if kind in ("torus", "torus-curve"):
        n = int(arg)
        shape = shapes.torus(n, R=1.0, r=0.3, n_curve=64, seed=0)
        rng = np.random.default_rng(0)
        cloud = shape.cloud
        skeletal = None if curve_only else shape.skeletal + rng.normal(scale=0.01, size=shape.skeletal.shape)
        curve = (shape.curve_vertices, shape.curve_edges)
        out["case"] = f"torus {n}" + (", curve only" if curve_only else "")
    else:
        from skelcore.io import load_cloud
        from skelcore.skeleton import skeletonize

        cloud = load_cloud(arg)
        t0 = time.perf_counter()
        skeletal, curve = skeletonize(cloud)
        out["skeletonize"] = time.perf_counter() - t0
        out["case"] = Path(arg).stem
    out["n_points"] = int(len(cloud))
    # the stages run side by side (evaluate's workers): a cancel stops the evaluation once every running
    # stage has reached its next check, so the gaps are measured per thread (the stage that thread runs)
    gaps = {"worst": 0.0, "stage": ""}
    last = {threading.get_ident(): time.perf_counter()}
    stage_of: dict = {}
    stage = [""]

    def progress(_fraction: float, name: str) -> None:
        if name != stage[0]:  # for the parent: the stage a case was in when its time ran out
            print(f"stage {name} {time.perf_counter() - t_start:.1f}", file=sys.stderr, flush=True)
        stage[0] = name
        stage_of[threading.get_ident()] = name

    def cancel() -> bool:
        now = time.perf_counter()
        me = threading.get_ident()
        gap = now - last.get(me, now)
        if gap > gaps["worst"]:
            gaps["worst"], gaps["stage"] = gap, stage_of.get(me, stage[0])
        last[me] = now
        return False

    cpu0 = time.process_time()
    ev = evaluate(cloud, skeletal, curve, Params(boundedness_method=method), progress=progress, cancel=cancel)
    out["cpu"] = time.process_time() - cpu0
    out.update(ev.timings)
    out["cancel_gap"], out["cancel_stage"] = gaps["worst"], gaps["stage"]
    if kind == "real":  # the same evaluation again in the same process: no first-call loading
        out["second"] = evaluate(cloud, skeletal, curve, Params(boundedness_method=method)).timings["total"]
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


def _child(kind: str, arg: str, method: str, timeout: float) -> dict | None:
    try:
        proc = subprocess.run(
            [sys.executable, __file__, "--method", method, "--child", kind, arg], capture_output=True, text=True,
            timeout=timeout,
        )
    except subprocess.TimeoutExpired as exc:
        err = exc.stderr.decode() if isinstance(exc.stderr, bytes) else (exc.stderr or "")
        stages = [ln.split()[1:] for ln in err.splitlines() if ln.startswith("stage ")]
        where = " ".join(stages[-1][:-1]) if stages else "start-up"
        since = float(stages[-1][-1]) if stages else 0.0
        print(f"| {kind} {arg} | did not finish in {timeout:.0f} s: in '{where}' since {since:.0f} s |", flush=True)
        return None
    if proc.returncode != 0:
        tail = proc.stderr.strip().splitlines()[-1] if proc.stderr.strip() else str(proc.returncode)
        print(f"| {kind} {arg} | failed: {tail} |", flush=True)
        return None
    return json.loads(proc.stdout.strip().splitlines()[-1])


def _row(r: dict) -> str:
    cells = [r["case"], str(r["n_points"])] + [f"{r[s]:.3f}" if s in r else "" for s in STAGES]
    cells += [f"{r['total']:.2f}", f"{r['cpu']:.2f}", f"{r['startup']:.2f}", f"{r['peak_mb']:.0f}",
              f"{r['cancel_gap']:.3f} ({r['cancel_stage']})" if "cancel_gap" in r else ""]
    if "skeletonize" in r:
        cells[0] += f" (skeletonize {r['skeletonize']:.1f} s; again in-process {r['second']:.2f} s)"
    return "| " + " | ".join(cells) + " |"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="*", default=[16384, 65536, 262144, 1048576])
    ap.add_argument("--method", default="rays", choices=("rays", "paper"))
    ap.add_argument("--no-real", action="store_true", help="skip ../shared/data clouds")
    ap.add_argument("--no-targets", action="store_true", help="only the size series (no Rips, no 100k, no curve-only)")
    ap.add_argument("--timeout", type=float, default=900.0, help="seconds per case before it is stopped")
    ap.add_argument("--ratio-runs", type=int, default=0, metavar="N",
                    help="then N more pairs of (gudhi Rips H0, hammer) fresh processes, alternating, and the "
                         "median of their ratios (this VM's speed drifts between minutes)")
    ap.add_argument("--child", nargs=2, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        print(json.dumps(run_case(args.child[0], args.child[1], args.method)))
        return
    print(f"machine: {_cpu_model()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
          f"load average at start {os.getloadavg()[0]:.1f}", flush=True)
    head = ["case", "points"] + [s.replace("skeletal ", "skel ") for s in STAGES]
    head += ["total s", "CPU s", "start-up s", "peak MB", "worst cancel gap s (stage)"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head), flush=True)
    res: dict[str, dict] = {}
    hammer = SHARED / "hammer_4096.ply"
    cases: list[tuple[str, str]] = []
    if not args.no_real and SHARED.is_dir():
        if not args.no_targets and hammer.is_file():
            cases.append(("rips", str(hammer)))
        cases += [("real", str(p)) for p in sorted(SHARED.glob("*.ply")) if "mesh" not in p.stem]
    if not args.no_targets:
        cases += [("torus", "100000"), ("torus-curve", "1048576")]
    cases += [("torus", str(n)) for n in args.sizes]
    for kind, arg in cases:
        r = _child(kind, arg, args.method, args.timeout)
        if r is None:
            continue
        res[r["case"]] = r
        print(_row(r), flush=True)
    print(f"\nload average at end {os.getloadavg()[0]:.1f}")
    rips = next((r for k, r in res.items() if k.startswith("gudhi")), None)
    ham = res.get("hammer_4096")
    print("\n| target | measured | goal |\n|---|---|---|")
    if rips and ham:
        print(f"| hammer full evaluation (fresh process) / gudhi Rips H0 | {ham['total']:.2f} s / {rips['total']:.2f} s "
              f"= {ham['total'] / rips['total']:.3f} (again in-process {ham['second'] / rips['total']:.3f}) | <= 0.02 |")
    for key, goal in (("torus 100000", "<= 5 s"), ("torus 1048576", "<= 60 s, <= 4 GB"),
                      ("torus 1048576, curve only", "<= 3 s")):
        if key in res:
            print(f"| {key} | {res[key]['total']:.2f} s, {res[key]['peak_mb']:.0f} MB | {goal} |")
    apple = next((r for k, r in res.items() if k.startswith("apple")), None)
    if apple:
        print(f"| apple tree with the built-in skeleton, evaluation | {apple['total']:.2f} s | <= 2 s |")
    sizes = sorted(n for n in args.sizes if f"torus {n}" in res)
    for a, b in zip(sizes, sizes[1:]):
        print(f"| growth torus {a} -> {b} | x{res[f'torus {b}']['total'] / res[f'torus {a}']['total']:.2f} "
              f"for x{b / a:.0f} points | <= 4.5 per 4x |")
    if args.ratio_runs > 0 and hammer.is_file():
        ratios = []
        for _ in range(args.ratio_runs):
            pair = [_child("rips", str(hammer), args.method, args.timeout), _child("real", str(hammer), args.method, args.timeout)]
            if None in pair:
                continue
            ratios.append((pair[1]["total"] / pair[0]["total"], pair[1]["total"], pair[0]["total"]))
        if ratios:
            listed = ", ".join(f"{h:.2f}/{r:.2f} s = {q:.3f}" for q, h, r in ratios)
            print(f"| hammer / Rips in {len(ratios)} alternating pairs | {listed}; median "
                  f"{sorted(q for q, _, _ in ratios)[len(ratios) // 2]:.3f} | <= 0.02 |")
    gaps = [(r["cancel_gap"], k, r["cancel_stage"]) for k, r in res.items() if "cancel_gap" in r]
    if gaps:
        g, k, s = max(gaps)
        print(f"| worst cancel gap seen | {g:.3f} s ({k}, {s}) | <= 0.5 s at 1M |")


if __name__ == "__main__":
    main()
