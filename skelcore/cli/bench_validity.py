"""``skelcore bench validity --out DIR``: which metric sees which defect
(:mod:`skelcore.benchmark.validity`, docs/validity.md)."""

from __future__ import annotations

import argparse
import os
import signal
import sys

from ..errors import SkelInputError
from .common import positive_int

__all__ = ["register_validity", "run_validity_cli"]


def register_validity(actions: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add the ``validity`` action to ``skelcore bench``."""
    p = actions.add_parser(
        "validity",
        help="which metric sees which defect: controlled defects of the exact skeletons, every metric, AUC",
        description="Apply controlled defects at graded sizes to the benchmark shapes' exact curve skeletons, "
        "score the clean and defective skeletons with every metric (the paper's four, coverage, the "
        "diagnostics, the ground-truth metrics) and write scores.csv, validity.csv, validity.md and "
        "validity.png into DIR: per metric and defect the detection AUC and the Spearman correlation with "
        "the ground-truth error. DIR must be new, empty or an earlier validity run (resumed).",
    )
    p.add_argument("--out", required=True, metavar="DIR",
                   help="output folder (new, empty, or a validity run: resumed)")
    p.add_argument("--suite", choices=("default", "small", "neurons"), default="default",
                   help="default: 12 shapes at 5000 points, 3 seeds; small: 3 shapes at 1200 points, 2 seeds; "
                   "neurons: the 5 traced neurons of resources/neurons at 3000 points, 1 seed")
    p.add_argument("--seed", type=int, default=0, metavar="N",
                   help="the suite seed shapes and defects are drawn from (0)")
    p.add_argument("--seeds", type=positive_int, metavar="K", help="clouds (and defect draws) per shape (the suite's)")
    p.add_argument("--points", type=positive_int, metavar="N", help="points per cloud (the suite's)")
    p.add_argument("--shapes", nargs="+", metavar="NAME", help="only these benchmark shapes")
    p.add_argument("--defects", nargs="+", metavar="NAME",
                   help="only these defects (docs/validity.md lists the ten; an unknown name lists them too)")
    p.add_argument("--backend", choices=("pool", "dask", "serial"), default="pool",
                   help="a local process pool (default), Dask, or this process")
    p.add_argument("--workers", type=positive_int, metavar="N", help="workers of the pool or the Dask LocalCluster "
                   "(default: one per core)")
    p.add_argument("--scheduler", metavar="ADDR", help="with --backend dask: tcp://HOST:PORT of a running scheduler "
                   "(default: a LocalCluster of --workers)")
    p.add_argument("--force", action="store_true",
                   help="write into an existing DIR that is not a validity run (files of the same names are replaced)")
    p.add_argument("--no-figure", action="store_true", help="skip validity.png")
    p.add_argument("--quiet", action="store_true", help="no line per task")
    p.set_defaults(func=run_validity_cli)
    return p


def _backend(args: argparse.Namespace):
    from ..compare.backends import Backend, parse_backend

    workers = args.workers or (os.cpu_count() or 1)
    if args.seed < 0:
        raise SkelInputError(f"--seed must be a whole number >= 0, got {args.seed}")
    if args.scheduler and args.backend != "dask":
        raise SkelInputError("--scheduler needs --backend dask")
    if args.backend == "serial":
        return Backend("serial", 1)
    if args.backend == "pool":
        return Backend("pool", workers)
    return parse_backend(None, args.scheduler or f"local:{workers}")


def _terminate(signum, frame):  # noqa: ARG001
    raise SystemExit(128 + signum)


def run_validity_cli(args: argparse.Namespace) -> int:
    from ..benchmark.validity import run_validity, validity_tasks
    from ..benchmark.validity_stats import blind_spots

    def progress(i: int, total: int, key: str, status: str) -> None:
        if not args.quiet:
            print(f"[{i}/{total}] {key}: {status}", file=sys.stderr, flush=True)

    previous = signal.signal(signal.SIGTERM, _terminate)
    try:
        backend = _backend(args)
        tasks = validity_tasks(args.suite, seed=args.seed, seeds=args.seeds, shapes=args.shapes,
                               defects=args.defects, points=args.points)
        result = run_validity(args.out, tasks, backend, force=args.force, figure=not args.no_figure,
                              progress=progress, suite=args.suite)
    except SkelInputError as exc:
        print(f"skelcore: error: {exc}", file=sys.stderr)
        return 2
    finally:
        signal.signal(signal.SIGTERM, previous)
    for name, table in result.tables.items():
        for metric, blind in blind_spots(table).items():
            print(f"{name} {metric}: blind to {', '.join(blind) if blind else 'none'}")
    print(f"{result.tasks} tasks: {result.kept} already done, {result.ran} ran, {len(result.failed)} failed; "
          f"{len(result.rows)} scored skeletons; {result.backend}, {result.wall:.1f} s")
    for rec in result.failed:
        print(f"failed: {rec['key']}: {rec['error']}")
    print(f"results in {result.folder} (scores.csv, validity.csv, validity.md"
          + ("" if args.no_figure else ", validity.png") + ")")
    return 0
