"""``skelcore bench make DIR``: write a benchmark of generated shapes with exact curve skeletons
(:mod:`skelcore.benchmark`)."""

from __future__ import annotations

import argparse
import sys
import time

from ..errors import SkelInputError
from .common import nonnegative_int

__all__ = ["register", "run_bench_make_cli"]


def register(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add ``skelcore bench make DIR [--suite default|small|real|real-small] [--sizes N,N] [--seed N]
    [--force] [--quiet]``."""
    p = subparsers.add_parser(
        "bench",
        help="benchmark with ground truth: generated shapes, exact curve skeletons, scan effects",
        description="Benchmarks with ground truth.",
    )
    sub = p.add_subparsers(dest="bench_command", required=True, metavar="ACTION")
    make = sub.add_parser(
        "make",
        help="write the benchmark's clouds, exact skeletons, suite.json and a compare manifest into DIR",
        description="Write every case of a suite into DIR: clouds/{case}.ply, truth/{case}_reference.ply "
        "(the exact curve skeleton with a per-vertex radius), cases/{case}.json, suite.json and "
        "compare.toml (skelcore compare with the built-in skeletonizers). Deterministic from --seed; "
        "a rerun skips finished cases. DIR must be new, empty or a benchmark folder.",
    )
    make.add_argument("dir", metavar="DIR", help="the benchmark folder")
    make.add_argument("--suite", choices=("default", "small", "real", "real-small"), default="default",
                      help="default: 120 cases, about 35 s to write, a few minutes of compare with cao; "
                      "small: 10 cases of about 1200 points (tests); real: the five traced neurons of "
                      "resources/neurons sampled from their meshes, clean and under scan effects, their "
                      "SWC skeletons as ground truth (docs/benchmark.md); real-small: one neuron at 30k, clean")
    make.add_argument("--sizes", type=_sizes, default=None, metavar="N,N",
                      help="real suites only: the clouds' sizes in points (default 30000,100000,300000 for "
                      "real, 30000 for real-small), e.g. --sizes 30000,100000 to skip the largest")
    make.add_argument("--seed", type=nonnegative_int, default=0, metavar="N", help="the seed every shape and scan is drawn from (0)")
    make.add_argument("--force", action="store_true",
                      help="remake every case, also in a folder that is not a benchmark or holds another "
                      "suite or seed (files of the same names are replaced)")
    make.add_argument("--quiet", action="store_true", help="no line per case")
    make.set_defaults(func=run_bench_make_cli)
    from .bench_repair import register_repair
    from .bench_validity import register_validity

    register_validity(sub)
    from .bench_calibrate import register_calibrate

    register_calibrate(sub, _sizes)
    register_repair(sub)
    return p


def _sizes(text: str) -> list[int]:
    """``--sizes 30000,100000``: whole numbers >= 1000 (k for thousands allowed: 30k)."""
    out = []
    for tok in text.split(","):
        t = tok.strip().lower()
        try:
            n = int(float(t[:-1]) * 1000) if t.endswith("k") else int(t)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{tok.strip()!r} is not a number of points") from None
        if n < 1000:
            raise argparse.ArgumentTypeError(f"{n} points is too few (at least 1000)")
        out.append(n)
    return sorted(set(out))


def run_bench_make_cli(args: argparse.Namespace) -> int:
    from ..benchmark import make_benchmark

    start = time.perf_counter()

    def progress(i: int, total: int, case: str, status: str) -> None:
        if not args.quiet:
            print(f"[{i}/{total}] {case}: {status}", file=sys.stderr, flush=True)

    try:
        result = make_benchmark(args.dir, args.suite, args.seed, force=args.force, progress=progress,
                                sizes=args.sizes)
    except SkelInputError as exc:
        print(f"skelcore: error: {exc}", file=sys.stderr)
        return 2
    print(f"{len(result.records)} cases of the {result.suite!r} suite (seed {result.seed}) in {result.folder}: "
          f"{result.made} made, {result.kept} already there; {time.perf_counter() - start:.1f} s")
    print(f"run them: skelcore compare {result.folder / 'compare.toml'} --out RUN_DIR")
    return 0
