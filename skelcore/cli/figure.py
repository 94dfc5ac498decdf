"""``skelcore figure DIR -o FIG.png|.pdf``: the graphic table of a compare run, for a paper."""

from __future__ import annotations

import argparse
import sys

from ..errors import SkelInputError

__all__ = ["register", "run_figure_cli"]


def register(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "figure",
        help="the paper's graphic table of a compare run (skeleton, barcodes, coloured metrics)",
        description="Draw one row per shape, condition and method of a finished `skelcore compare` run.",
    )
    p.add_argument("dir", help="the compare output folder")
    p.add_argument("-o", "--output", required=True, metavar="FIG", help="FIG.png, FIG.pdf or FIG.svg")
    p.add_argument("--shapes", nargs="+", metavar="NAME", help="only these shapes")
    p.add_argument("--methods", nargs="+", metavar="NAME", help="only these methods")
    p.add_argument("--conditions", nargs="+", metavar="NAME", help="only these conditions")
    p.add_argument("--dpi", type=int, default=150, help="resolution of a PNG (default 150)")
    p.set_defaults(func=run_figure_cli)
    return p


def run_figure_cli(args: argparse.Namespace) -> int:
    from ..compare.figure import make_figure

    try:
        n = make_figure(args.dir, args.output, shapes=args.shapes, methods=args.methods,
                        conditions=args.conditions, dpi=args.dpi)
    except SkelInputError as exc:
        print(f"skelcore: error: {exc}", file=sys.stderr)
        return 2
    print(f"{args.output}: {n} rows")
    return 0
