"""``skelcore compare MANIFEST.toml --out DIR``: rank skeletonizers over a dataset
(:mod:`skelcore.compare`)."""

from __future__ import annotations

import argparse
import signal
import sys

from ..errors import SkelInputError
from .common import positive_int

__all__ = ["register", "run_compare_cli"]


def register(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "compare",
        help="rank skeletonizers over a dataset: jobs on a local pool or a Dask cluster, leaderboard, report",
        description="Run every (shape, method, condition, seed) of the manifest, resumably, and write "
        "results.csv, leaderboard.md/.csv/.tex and report.html in DIR.",
    )
    p.add_argument("manifest", help="the manifest (TOML; paths relative to its folder)")
    p.add_argument("--out", required=True, metavar="DIR",
                   help="output folder: new, empty, or an earlier run (resumed: finished jobs are skipped)")
    p.add_argument("--force", action="store_true",
                   help="write into an existing --out that is not a compare run (files of the same names are replaced)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--jobs", type=positive_int, metavar="N", help="local worker processes (default: one per core)")
    g.add_argument("--dask", metavar="ADDR", help="tcp://HOST:PORT of a Dask scheduler, or local:N for a LocalCluster")
    p.add_argument("--profiles", metavar="F", help="application profiles TOML (default: the shipped ones)")
    p.add_argument("--retry-failed", action="store_true", help="run failed jobs again (finished ones are kept)")
    p.add_argument("--no-report", action="store_true", help="skip report.html (its renders take a while)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=run_compare_cli)
    return p


def _terminate(signum, frame):  # noqa: ARG001
    raise SystemExit(128 + signum)


def run_compare_cli(args: argparse.Namespace) -> int:
    from ..compare import parse_backend, run_compare

    previous = signal.signal(signal.SIGTERM, _terminate)  # unwind: stop the workers, keep what is stored
    try:
        backend = parse_backend(args.jobs, args.dask)
        result = run_compare(args.manifest, args.out, backend, profiles_path=args.profiles,
                             report=not args.no_report, quiet=args.quiet, retry_failed=args.retry_failed,
                             force=args.force)
    except SkelInputError as exc:
        print(f"skelcore: error: {exc}", file=sys.stderr)
        return 2
    finally:
        signal.signal(signal.SIGTERM, previous)
    s = result.summary
    print(result.leaderboard.to_markdown(), end="")
    if result.leaderboard.sound is not None:
        print("\nOver the cases where every method is sound:\n")
        print(result.leaderboard.sound.to_markdown(), end="")
    print(f"{s.total} jobs: {s.skipped} already done, {s.ok} ran ok, {s.failed} failed; "
          f"{s.backend}, {s.wall:.1f} s")
    for rec in s.records:
        if rec["status"] != "ok":
            print(f"failed: {rec['shape']} / {rec['method']} / {rec['condition']} / seed {rec['seed']}: {rec['error']}")
    print(f"results in {args.out} (results.csv, leaderboard.md/.csv/.tex, leaderboard_sound.md/.csv/.tex" + ("" if args.no_report else ", report.html") + ")")
    return 0
