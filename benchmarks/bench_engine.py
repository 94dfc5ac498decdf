"""Engine speed against its targets: full evaluations by size, real scans, cancel latency.

Every case runs in a fresh subprocess, so its time includes the fresh process's first call
("start-up" = interpreter + imports, reported separately) and its peak resident memory (ru_maxrss) is its own; CPU s = process time of
all threads (the fairer figure when other jobs share the cores).  Generated shapes: a torus
(R = 1, r = 0.3) sampled with N points, skeletal set = each point's projection onto the core circle
+ 1 % jitter, curve = a 64-gon of the core circle.  Real clouds from resources/scans/ are scored
against the built-in skeletonizer's output (its time reported apart).  The yardstick: gudhi's
Vietoris-Rips H0 of the hammer scan, timed in the same run.  The worst cancel latency is the longest
gap between two cancel checks of a run (the cancel callback times itself).  "diag" = the diagnostics'
stages (curve defects, skeletal and curve missing parts), their seconds and their share of
all stages' seconds (the stages run side by side, so shares of the summed stage times), and their CPU
seconds when run again alone on the same inputs over the evaluation's CPU seconds (robust to load).
"torus N, coverage + diagnostics": coverage_max_points raised above N (the 1M case; above
coverage_exact_points coverage is estimated on a subsample).  "viewpoint": the front half of a
cylinder (2N points, y > 0) with its axis as skeletal set, plain and viewpoint-aware boundedness of the
same elements, CPU seconds and their ratio.

    .venv/bin/python benchmarks/bench_engine.py                 # the target table
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
SCANS = ROOT / "resources" / "scans"
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
    "stray points",
]
DIAG = ["curve defects", "skeletal missing parts", "curve missing parts"]


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
    if kind == "viewpoint":
        return out | _viewpoint_case(int(arg))
    curve_only = kind == "torus-curve"
    params = Params(boundedness_method=method)
    if kind == "torus-cov":
        params = Params(boundedness_method=method, coverage_max_points=int(arg) + 1)
    if kind in ("torus", "torus-curve", "torus-cov"):
        n = int(arg)
        shape = shapes.torus(n, R=1.0, r=0.3, n_curve=64, seed=0)
        rng = np.random.default_rng(0)
        cloud = shape.cloud
        skeletal = None if curve_only else shape.skeletal + rng.normal(scale=0.01, size=shape.skeletal.shape)
        curve = (shape.curve_vertices, shape.curve_edges)
        out["case"] = f"torus {n}" + (", curve only" if curve_only else "") + (
            ", coverage + diagnostics" if kind == "torus-cov" else "")
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
    ev = evaluate(cloud, skeletal, curve, params, progress=progress, cancel=cancel)
    out["cpu"] = time.process_time() - cpu0
    out.update(ev.timings)
    stage_sum = sum(v for k, v in ev.timings.items() if k != "total")
    out["diag"] = sum(ev.timings.get(k, 0.0) for k in DIAG)
    out["diag_share"] = out["diag"] / stage_sum if stage_sum > 0 else 0.0
    if kind != "real":
        out["diag_cpu"] = _diagnostics_cpu(cloud, skeletal, curve, params, ev)
        out["diag_cpu_share"] = out["diag_cpu"] / max(out["cpu"], 1e-9)
    covs = [c for c in (ev.coverage_skeletal, ev.coverage_curve) if c is not None]
    out["coverage_subsample"] = next((c.subsample for c in covs if c.subsample), None)
    out["cancel_gap"], out["cancel_stage"] = gaps["worst"], gaps["stage"]
    if kind == "real":  # the same evaluation again in the same process: no first-call loading
        out["second"] = evaluate(cloud, skeletal, curve, Params(boundedness_method=method)).timings["total"]
    out["peak_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    return out


def _diagnostics_cpu(cloud, skeletal, curve, params, ev) -> float:
    """CPU seconds (all threads) of the diagnostics' stages run again alone on the evaluation's inputs,
    with its curve boundedness and coverage as they read them (load-proof, unlike side-by-side walls)."""
    from skelcore.geometry import no_checkpoint
    from skelcore.stages.catalogue import CATALOGUE
    from skelcore.stages.context import build_context

    ctx = build_context(cloud, skeletal, curve, params, skeletal_index=None, correspondence="auto",
                        reference_curve=None)
    if ev.curve is not None:
        ctx.results["curve boundedness"] = ev.curve.sample_boundedness
    for key, cov in (("skeletal coverage", ev.coverage_skeletal), ("curve coverage", ev.coverage_curve)):
        if cov is not None:
            ctx.results[key] = cov
    c0 = time.process_time()
    for stage in CATALOGUE:
        if stage.name in DIAG and stage.applies(ctx):
            stage.fn(ctx, no_checkpoint)
    return time.process_time() - c0


def _viewpoint_case(n: int) -> dict:
    """Plain and viewpoint-aware boundedness of the same elements (CPU s of all threads)."""
    import numpy as np

    from skelcore import Params, shapes
    from skelcore.geometry import Normalization
    from skelcore.metrics.boundedness import boundedness
    from skelcore.scan.viewpoint import seen_boundedness

    c = shapes.cylinder(2 * n)
    keep = c.cloud[:, 1] > 0
    p = Params()
    norm = Normalization.from_cloud(c.cloud[keep], p.normalize_by, p.normalized_size)
    cloud, queries = norm.apply(c.cloud[keep]), norm.apply(c.skeletal[keep])
    vp = norm.apply(np.array([[0.0, 40.0, 2.0]]))
    out: dict = {"case": f"viewpoint, front half of a cylinder", "n_points": int(len(cloud))}
    t0, c0 = time.perf_counter(), time.process_time()
    plain = boundedness(cloud, queries, params=p)
    out["plain"], out["plain_cpu"] = time.perf_counter() - t0, time.process_time() - c0
    t0, c0 = time.perf_counter(), time.process_time()
    seen = seen_boundedness(cloud, queries, vp, params=p, return_missing=True)[0]
    out["seen"], out["seen_cpu"] = time.perf_counter() - t0, time.process_time() - c0
    out["plain_score"] = float(np.mean(plain > p.beta_star))
    out["seen_score"] = float(np.mean(seen > p.beta_star))
    import resource

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
    if "seen" in r:
        return (f"| {r['case']} | {r['n_points']} | plain boundedness {r['plain']:.2f} s ({r['plain_cpu']:.2f} CPU s, "
                f"score {r['plain_score']:.3f}); viewpoint-aware {r['seen']:.2f} s ({r['seen_cpu']:.2f} CPU s, score "
                f"{r['seen_score']:.3f}); CPU ratio x{r['seen_cpu'] / max(r['plain_cpu'], 1e-9):.1f} |")
    cells = [r["case"], str(r["n_points"])] + [f"{r[s]:.3f}" if s in r else "" for s in STAGES]
    cells += [f"{r['diag']:.3f} ({100 * r['diag_share']:.0f} %)" if "diag" in r else ""]
    cells += [f"{r['diag_cpu']:.2f} ({100 * r['diag_cpu_share']:.0f} %)" if "diag_cpu" in r else ""]
    cells += [f"{r['total']:.2f}", f"{r['cpu']:.2f}", f"{r['startup']:.2f}", f"{r['peak_mb']:.0f}",
              f"{r['cancel_gap']:.3f} ({r['cancel_stage']})" if "cancel_gap" in r else ""]
    if r.get("coverage_subsample"):
        cells[0] += f" (coverage on a subsample of {r['coverage_subsample']:,})"
    if "skeletonize" in r:
        cells[0] += f" (skeletonize {r['skeletonize']:.1f} s; again in-process {r['second']:.2f} s)"
    return "| " + " | ".join(cells) + " |"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="*", default=[16384, 65536, 262144, 1048576])
    ap.add_argument("--method", default="rays", choices=("rays", "paper"))
    ap.add_argument("--no-real", action="store_true", help="skip the real scans (resources/scans)")
    ap.add_argument("--no-targets", action="store_true", help="only the size series (no Rips, no 100k, no curve-only)")
    ap.add_argument("--timeout", type=float, default=900.0, help="seconds per case before it is stopped")
    ap.add_argument("--coverage-sizes", type=int, nargs="*", default=[1048576],
                    help="torus sizes also run with coverage (coverage_max_points raised) and diagnostics")
    ap.add_argument("--viewpoint-sizes", type=int, nargs="*", default=[65536],
                    help="elements of the viewpoint case (front half of a 2N-point cylinder)")
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
    head = ["case", "points"] + [s.replace("skeletal ", "skel ") for s in STAGES] + ["diag s (share)", "diag CPU s alone (share of CPU)"]
    head += ["total s", "CPU s", "start-up s", "peak MB", "worst cancel gap s (stage)"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head), flush=True)
    res: dict[str, dict] = {}
    hammer = SCANS / "hammer_4096.ply"
    cases: list[tuple[str, str]] = []
    if not args.no_real:
        if not args.no_targets:
            cases.append(("rips", str(hammer)))
        cases += [("real", str(SCANS / f"{stem}.ply")) for stem in ("apple_tree_22367", "cave_27375", "hammer_4096")]
    if not args.no_targets:
        cases += [("torus", "100000"), ("torus-curve", "1048576")]
    cases += [("torus", str(n)) for n in args.sizes]
    cases += [("torus-cov", str(n)) for n in args.coverage_sizes]
    cases += [("viewpoint", str(n)) for n in args.viewpoint_sizes]
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
    for key, r in res.items():
        if key.endswith("coverage + diagnostics"):
            print(f"| {key} | {r['total']:.2f} s, {r['cpu']:.1f} CPU s, {r['peak_mb']:.0f} MB | < 25 s |")
    shares = [(r["diag_share"], k) for k, r in res.items() if "diag_share" in r]
    if shares:
        top, key = max(shares)
        print(f"| diagnostics' largest share of the stages' time | {100 * top:.0f} % ({key}) | <= 25 % |")
    shares = [(r["diag_cpu_share"], k) for k, r in res.items() if "diag_cpu_share" in r]
    if shares:
        top, key = max(shares)
        print(f"| diagnostics' largest CPU alone / the evaluation's CPU | {100 * top:.0f} % ({key}) | <= 25 % |")
    for key, r in res.items():
        if "seen" in r:
            print(f"| viewpoint-aware / plain boundedness, {r['n_points']} cloud points | "
                  f"x{r['seen_cpu'] / max(r['plain_cpu'], 1e-9):.1f} CPU ({r['seen_cpu']:.2f} / {r['plain_cpu']:.2f} s) | <= x3 |")
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
