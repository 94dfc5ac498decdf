"""``skelcore evaluate``: score a skeleton against its cloud and print the paper's table."""

from __future__ import annotations

import argparse
import os

from ..errors import SkelInputError
from .common import clear_progress_line, format_table, params_from_args, stderr_progress

__all__ = ["register", "run_evaluate"]


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``skelcore evaluate CLOUD ...``."""
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
    from .. import io
    from ..evaluate import evaluate
    from ..io.export import export_ply

    params = params_from_args(args)
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
    clear_progress_line(progress)
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
