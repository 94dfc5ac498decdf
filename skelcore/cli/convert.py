"""``skelcore convert IN OUT``: any readable curve or point set to any writable format, read back and
compared (vertex and edge counts, components, cycles, the largest coordinate change); with
--skeleton-scale/--skeleton-offset written mapped into another frame (a skeleton into its cloud's)."""

from __future__ import annotations

import argparse
import sys

__all__ = ["register", "run_convert_cli"]


def register(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add ``skelcore convert IN OUT [--lossy] [--force] [--as curve|points] [--ascii]
    [--skeleton-scale S] [--skeleton-offset X Y Z]``."""
    p = subparsers.add_parser(
        "convert",
        help="convert a curve skeleton or point set to another format, then read it back and compare",
        description="Write IN in OUT's format (by extension: curves to .ply .obj .swc .cg .graphml .json, "
        "point sets to .ply .xyz .txt .npy .obj .graphml .json), read OUT back and print what it holds "
        "beside IN. A format that cannot hold the input (a cycle in SWC, radii in OBJ or .cg, edges in "
        "XYZ) is refused with the reason unless --lossy. IN is never overwritten.",
    )
    p.add_argument("input", metavar="IN", help="curve skeleton or point set (any format skelcore reads)")
    p.add_argument("output", metavar="OUT", help="file to write; its extension picks the format")
    p.add_argument("--lossy", action="store_true", help="write even when OUT's format loses something")
    p.add_argument("--force", action="store_true", help="replace OUT when it exists")
    p.add_argument("--as", dest="as_kind", choices=("curve", "points"),
                   help="read IN as this (default: a file with edges is a curve, else a point set)")
    p.add_argument("--ascii", action="store_true", help="write PLY as text (default: binary)")
    p.add_argument("--skeleton-scale", type=float, metavar="S", default=1.0,
                   help="multiply the coordinates (and a curve's radii) by S ...")
    p.add_argument("--skeleton-offset", type=float, nargs=3, metavar=("X", "Y", "Z"), default=(0.0, 0.0, 0.0),
                   help="... then add this offset: the map of skelcore evaluate's flags of these names, to write "
                   "a skeleton in its cloud's frame")
    p.set_defaults(func=run_convert_cli)
    return p


def run_convert_cli(args: argparse.Namespace) -> int:
    from ..errors import SkelInputError
    from ..io.conversion import convert_file

    try:
        result = convert_file(args.input, args.output, lossy=args.lossy, force=args.force, as_kind=args.as_kind,
                              binary=not args.ascii, scale=args.skeleton_scale,
                              offset=tuple(args.skeleton_offset))
    except SkelInputError as exc:
        print(f"skelcore: error: {exc}", file=sys.stderr)
        return 2
    print(f"in : {args.input} ({result.source.line()})")
    if (args.skeleton_scale, tuple(args.skeleton_offset)) != (1.0, (0.0, 0.0, 0.0)):
        off = " ".join(f"{x:.9g}" for x in args.skeleton_offset)
        print(f"mapped: coordinates x {args.skeleton_scale:.9g} + ({off})")
    print(f"out: {args.output} ({result.written.line()})")
    change = f"largest coordinate change {result.max_coordinate_change:.3g}"
    if result.max_radius_change is not None:
        change += f", radius change {result.max_radius_change:.3g}"
    print(change)
    if result.lossy_reason:
        print(f"lossy (--lossy): {result.lossy_reason}")
        return 0
    if not result.same:
        print("skelcore: error: the file read back differs from the input", file=sys.stderr)
        return 1
    print("read back: the same")
    return 0
