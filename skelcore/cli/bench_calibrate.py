"""``skelcore bench calibrate --out DIR``: precision and recall of every warning code against
ground truth (:mod:`skelcore.benchmark.calibration`, docs/diagnostics.md "Precision and recall per
warning")."""

from __future__ import annotations

import argparse
import os
import platform
import shlex
import signal
import sys

from ..errors import SkelInputError
from .common import LazyChoices, positive_int

__all__ = ["register_calibrate", "run_calibrate_cli"]


def register_calibrate(actions: argparse._SubParsersAction, sizes) -> argparse.ArgumentParser:
    """Add the ``calibrate`` action to ``skelcore bench`` (``sizes`` parses --sizes); the suites and
    conditions are read from the calibration's grid only when a value is checked or the help shown."""
    p = actions.add_parser(
        "calibrate",
        help="precision and recall of every warning code: known defects injected, every scan condition",
        description="Inject known defects into the exact skeletons of the generated shapes and into the "
        "traced skeletons of the shipped neurons, evaluate them on clouds under each scan condition, count "
        "each warning code against its ground truth and write rows.csv, calibration.csv and calibration.md "
        "(precision, recall and false alarms with Wilson 95 %% intervals) into DIR. DIR must be new, empty or "
        "an earlier calibration run (resumed).",
    )
    p.add_argument("--out", required=True, metavar="DIR", help="output folder (new, empty, or a calibration run: resumed)")
    p.add_argument("--suite", nargs="+", choices=LazyChoices(_suites), default=["synthetic", "real"], metavar="NAME",
                   help="suites: synthetic (12 shapes at 5000 points), real (5 neurons at 30k), synthetic-small, "
                   "real-small (default: synthetic real)")
    p.add_argument("--sizes", type=sizes, default=None, metavar="N,N",
                   help="real suites: the clouds' sizes in points (default 30000), e.g. 30k,100k")
    p.add_argument("--points", type=sizes, default=None, metavar="N,N",
                   help="synthetic suites: the clouds' sizes in points (default 5000, small 1200)")
    p.add_argument("--shapes", nargs="+", metavar="NAME", help="only these shapes or neuron ids")
    p.add_argument("--conditions", nargs="+", choices=LazyChoices(_conditions), metavar="NAME",
                   help="only these scan conditions (%(choices)s)")
    p.add_argument("--kinds", nargs="+", metavar="NAME", help="only these skeleton kinds (intact, spurs, ...)")
    p.add_argument("--seed", type=int, default=0, metavar="N", help="the suite seed (0): the clouds of bench make")
    p.add_argument("--workers", type=positive_int, metavar="N", help="processes (default: one per core)")
    p.add_argument("--docs", metavar="FILE", help="also write the tables between the calibration markers of FILE "
                   "(docs/diagnostics.md)")
    p.add_argument("--force", action="store_true", help="write into an existing DIR that is not a calibration run")
    p.add_argument("--quiet", action="store_true", help="no line per task")
    p.set_defaults(func=run_calibrate_cli)
    return p


def _suites() -> list[str]:
    from ..benchmark.calibration.grid import SUITES

    return list(SUITES)


def _conditions() -> list[str]:
    from ..benchmark.calibration.grid import CONDITIONS

    return list(CONDITIONS)


def _terminate(signum, frame):  # noqa: ARG001
    raise SystemExit(128 + signum)


def _machine() -> str:
    try:
        load = ", ".join(f"{x:.1f}" for x in os.getloadavg())
    except OSError:
        load = "unknown"
    return f"{platform.machine()}, {os.cpu_count()} cores, load average at the end {load}"


def run_calibrate_cli(args: argparse.Namespace) -> int:
    from ..benchmark.calibration import calibration_tasks, run_calibration
    from ..benchmark.calibration.calib_tables import fill_docs, markdown, summary_rows
    from ..compare.backends import Backend

    def progress(i: int, total: int, key: str, status: str) -> None:
        if not args.quiet:
            print(f"[{i}/{total}] {key}: {status}", file=sys.stderr, flush=True)

    previous = signal.signal(signal.SIGTERM, _terminate)
    try:
        if args.seed < 0:
            raise SkelInputError(f"--seed must be a whole number >= 0, got {args.seed}")
        tasks = calibration_tasks(args.suite, sizes=args.sizes, points=args.points, shapes=args.shapes,
                                  conditions=args.conditions, kinds=args.kinds, seed=args.seed)
        workers = args.workers or (os.cpu_count() or 1)
        backend = Backend("serial", 1) if workers == 1 else Backend("pool", workers)
        command = "skelcore bench calibrate " + " ".join(shlex.quote(a) for a in sys.argv[3:]) \
            if sys.argv[1:3] == ["bench", "calibrate"] else "skelcore bench calibrate"
        result = run_calibration(args.out, tasks, backend, force=args.force, progress=progress,
                                 command=command, machine=_machine())
        if args.docs:
            fill_docs(args.docs, markdown(summary_rows(result.rows), command=command, machine=_machine(),
                                          wall=result.wall if result.ran else 0.0, rows=result.rows))
    except SkelInputError as exc:
        print(f"skelcore: error: {exc}", file=sys.stderr)
        return 2
    finally:
        signal.signal(signal.SIGTERM, previous)
    print(f"{result.tasks} tasks: {result.kept} already done, {result.ran} ran, {len(result.failed)} failed; "
          f"{len(result.rows)} evaluated skeletons; {result.backend}, {result.wall:.1f} s")
    for rec in result.failed:
        print(f"failed: {rec['key']}: {rec['error']}")
    print(f"results in {result.folder} (rows.csv, calibration.csv, calibration.md)")
    return 0
