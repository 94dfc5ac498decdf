"""``skelcore`` command line: evaluate a skeleton against its cloud; print the paper's table.

Exit codes: 0 success, 2 input error (one line on stderr), 130 interrupted.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import warnings
from typing import Sequence

from .errors import SkelInputError
from .params import Params


def _fmt_score(value: object, digits: int = 3) -> str:
    if value is None:
        return "-"
    v = float(value)  # type: ignore[arg-type]
    return "nan" if math.isnan(v) else f"{v:.{digits}f}"


def format_table(summary: dict) -> str:
    """The paper's results layout: rows d_B/d_Wp, boundedness, centeredness, smoothness;
    columns skeletal points / curve skeleton, each score with the number of elements it counted."""
    counts = summary["counts"]

    def cell(metric: str, kind: str) -> str:
        value = summary[metric][kind]
        if value is None:
            return "-"
        return f"{_fmt_score(value)} (n={counts[metric][kind]})"

    topo = summary["topology"]
    topo_cell = "-" if topo is None else f"{_fmt_score(topo['bottleneck'], 4)} / {_fmt_score(topo['wasserstein'], 4)}"
    rows = [
        ("metric", "skeletal points", "curve skeleton"),
        ("d_B / d_Wp", topo_cell, "-"),
        ("boundedness", cell("boundedness", "skeletal"), cell("boundedness", "curve")),
        ("centeredness", cell("centeredness", "skeletal"), cell("centeredness", "curve")),
        ("smoothness", cell("smoothness", "skeletal"), cell("smoothness", "curve")),
    ]
    widths = [max(len(r[i]) for r in rows) for i in range(3)]
    lines = []
    for k, r in enumerate(rows):
        lines.append("  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip())
        if k == 0:
            lines.append("  ".join("-" * w for w in widths))
    if topo is not None:
        lines.append(f"(eps* = {_fmt_score(topo['eps_star'], 5)}, K = {topo['n_bars']} bars compared)")
    return "\n".join(lines)


def stderr_progress(quiet: bool):
    """A ``progress(fraction, stage)`` that redraws one terminal line, or None when not a terminal."""
    if quiet or not sys.stderr.isatty():
        return None

    def progress(fraction: float, stage: str) -> None:
        print(f"\r{fraction * 100:5.1f}%  {stage[:40]:<40}", end="", file=sys.stderr, flush=True)

    return progress


def _add_evaluate(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("evaluate", help="score a skeleton against its point cloud")
    p.add_argument("cloud", help="original point cloud (PLY, PCD, XYZ/TXT/CSV/PTS, NPY/NPZ, OBJ, OFF)")
    p.add_argument("--skeletal", metavar="F", help="skeletal point set in pointwise correspondence with the cloud")
    p.add_argument("--curve", metavar="F", help="curve skeleton (PLY with edges, OBJ, CG, SWC, polylines, JSON/NPZ)")
    p.add_argument("--json", metavar="F", help="write the results as JSON")
    p.add_argument("--per-point", metavar="PREFIX", help="write PREFIX_skeletal.csv, PREFIX_curve_samples.csv, PREFIX_curve_vertices.csv")
    p.add_argument("--barcodes", metavar="F", help="write every H0 bar of both diagrams as CSV")
    p.add_argument("--export-ply", metavar="DIR", help="write coloured PLY files of the skeleton into DIR")
    p.add_argument("--boundedness-method", choices=("rays", "paper"), help="boundedness estimator (default rays)")
    p.add_argument("--set", metavar="NAME=VALUE", action="append", default=[], help="set any Params field (repeatable)")
    p.add_argument("--quiet", action="store_true", help="do not print progress")
    p.set_defaults(func=run_evaluate)


def run_evaluate(args: argparse.Namespace) -> int:
    from . import io
    from .evaluate import evaluate
    from .export import export_ply

    try:
        params = Params().with_strings(args.set)
        if args.boundedness_method:
            params = params.replace(boundedness_method=args.boundedness_method)
    except ValueError as exc:
        raise SkelInputError(str(exc)) from None
    if not (args.skeletal or args.curve):
        raise SkelInputError("nothing to evaluate: give --skeletal and/or --curve")
    cloud = io.load_cloud(args.cloud)
    skeletal = io.load_points(args.skeletal) if args.skeletal else None
    curve = io.load_curve(args.curve) if args.curve else None
    if skeletal is not None and len(skeletal) != len(cloud):
        raise SkelInputError(
            f"has {len(skeletal)} points but the cloud {args.cloud} has {len(cloud)}: "
            "a skeletal point set needs one point per cloud point",
            args.skeletal,
        )
    inputs = {"cloud": args.cloud, "skeletal": args.skeletal, "curve": args.curve}
    progress = stderr_progress(args.quiet)
    ev = evaluate(cloud, skeletal, curve, params, progress=progress, inputs=inputs)
    if progress is not None:
        print("\r" + " " * 48 + "\r", end="", file=sys.stderr)
    guard = tuple(p for p in inputs.values() if p)
    print(format_table(ev.summary()))
    print(f"boundedness estimator: {params.boundedness_method}; total {ev.timings['total']:.2f} s")
    if args.json:
        ev.write_json(args.json, inputs=guard)
    if args.per_point:
        ev.write_per_point(args.per_point, inputs=guard)
    if args.barcodes:
        if ev.topology is None:
            raise SkelInputError("--barcodes needs --skeletal (barcodes compare the cloud with the skeletal set)")
        ev.write_barcodes(args.barcodes, inputs=guard)
    if args.export_ply:
        os.makedirs(args.export_ply, exist_ok=True)
        export_ply(ev, args.export_ply, inputs=guard)
    return 0


def build_parser() -> argparse.ArgumentParser:
    from . import __version__

    parser = argparse.ArgumentParser(prog="skelcore", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"skelcore {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    _add_evaluate(sub)
    try:
        from . import study
    except ImportError:  # the study needs the optional skeletonizer dependencies
        study = None  # type: ignore[assignment]
    if study is not None:
        study.register_cli(sub)
        if hasattr(study, "register_skeletonize_cli"):
            study.register_skeletonize_cli(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    def one_line_warning(message, category, filename, lineno, file=None, line=None):  # noqa: ARG001
        print(f"skelcore: warning: {message}", file=sys.stderr)

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("default")
            warnings.showwarning = one_line_warning
            return int(args.func(args) or 0)
    except SkelInputError as exc:
        print(f"skelcore: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("skelcore: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
