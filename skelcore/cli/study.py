"""``skelcore study``: the paper's degradation study of one cloud (:mod:`skelcore.experiments.study`)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..errors import SkelInputError
from .common import (clear_progress_line, nonnegative_float, params_from_args, positive_float, positive_int,
                     stderr_progress)

__all__ = ["register", "run_study_cli"]


def register(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add ``skelcore study CLOUD ...``."""
    p = subparsers.add_parser(
        "study",
        help="the paper's study: skeletonize and score the cloud, a noisy and a sparse copy",
        description="Skeletonize the cloud, a noisy copy and a sparse copy, score each and print the "
        "paper's results table (skeletal/curve in every cell).",
    )
    p.add_argument("cloud", help="point cloud file")
    p.add_argument("--noise", type=nonnegative_float, default=0.05, help="noise ratio of the noise row (default 0.05; 0 = no row)")
    p.add_argument("--noise-model", choices=("reference", "isotropic"), default="reference",
                   help="reference: sigma = ratio x each coordinate (paper's toolbox); isotropic: ratio x RMS radius")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--sparse", type=positive_int, metavar="N", help="sparse row: N random points (default N/4)")
    g.add_argument("--grid", type=positive_float, metavar="CELL", help="sparse row: voxel-grid average of the input")
    p.add_argument("--base-grid", type=positive_float, metavar="CELL",
                   help="normal row: voxel-grid average of the input (paper's tree: 0.02 with --grid 0.05)")
    p.add_argument("--seed", type=int, default=0, help="seed of the noise and the downsampling (default 0)")
    p.add_argument("--out", metavar="DIR", help="write every variant's PLY/JSON files and study.md/.csv/.tex here")
    p.add_argument("--skeleton-cmd", metavar="CMD",
                   help="use this skeletonizer: a command with {in}, {out_skeletal} and/or {out_curve} "
                   "({python}: the interpreter running skelcore)")
    p.add_argument("--method", choices=("cao", "skelscope"), default="cao",
                   help="built-in skeletonizer: cao (the paper's toolbox algorithm, default) or skelscope")
    p.add_argument("--boundedness-method", choices=("rays", "paper"), help="boundedness estimator (default rays)")
    p.add_argument("--set", metavar="NAME=VALUE", action="append", default=[], help="set any Params field")
    p.add_argument("--quiet", action="store_true", help="do not print progress")
    p.set_defaults(func=run_study_cli)
    return p


def run_study_cli(args: argparse.Namespace) -> int:
    """Handler of ``skelcore study``: prints the table; 2 and one line on an input error."""
    from .. import io
    from ..experiments.study import run_study

    try:
        params = params_from_args(args)
        if args.out:
            io.atomic.check_output_dir(args.out)
        cloud = io.load_cloud(args.cloud)
        progress = stderr_progress(args.quiet)
        result = run_study(
            cloud,
            noise=args.noise,
            noise_model=args.noise_model,
            sparse=args.sparse,
            grid=args.grid,
            base_grid=args.base_grid,
            seed=args.seed,
            out_dir=args.out,
            skeleton_cmd=args.skeleton_cmd,
            method=args.method,
            params=params,
            name=Path(args.cloud).stem,
            inputs=(args.cloud,),
            progress=progress,
        )
        clear_progress_line(progress)
    except SkelInputError as exc:
        print(f"skelcore: error: {exc}", file=sys.stderr)
        return 2
    print(result.to_markdown(), end="")
    total = sum(sum(r.timings.values()) for r in result.rows)
    print(f"boundedness estimator: {params.boundedness_method}; noise model: {args.noise_model}; "
          f"seed {args.seed}; total {total:.1f} s")
    if args.out:
        print(f"files written to {args.out}")
    return 0
