"""``skelcore skeletonize``: contract a cloud and write its skeletal set and curve skeleton."""

from __future__ import annotations

import argparse
import sys

from ..errors import SkelInputError
from .common import clear_progress_line, stderr_progress

__all__ = ["register", "run_skeletonize_cli"]


def register(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add ``skelcore skeletonize CLOUD --out-skeletal F --out-curve F``."""
    p = subparsers.add_parser(
        "skeletonize",
        help="skeletonize a cloud (Laplacian contraction): skeletal points and curve skeleton",
        description="Laplacian-based contraction (Cao et al. 2010): writes the skeletal point set "
        "(one point per cloud point, same order) and the curve skeleton, each in its extension's format. "
        "The curve is then repaired "
        "from its defects (skelcore repair: each action kept only when nothing gets worse; docs/repair.md); "
        "--raw writes the algorithm's curve as it is. With --method cao and no --raw, a cloud whose parts are "
        "far thinner than cao's sampling ball (a neuron's dendrites) starts from the axis curve at the "
        "cloud's own spacing instead (docs/skeletonize.md, thin parts).",
    )
    p.add_argument("cloud", help="point cloud file")
    p.add_argument("--out-skeletal", metavar="F", help="write the skeletal point set (its extension picks the "
                   "format: .ply .xyz .txt .npy)")
    p.add_argument("--out-curve", metavar="F", help="write the curve skeleton (its extension picks the format: "
                   ".ply .obj .swc .cg .graphml .json)")
    p.add_argument("--method", choices=("cao", "skelscope"), default="cao",
                   help="cao: the paper's toolbox algorithm, step by step (default); skelscope: ours, "
                   "with clean-up of shortcuts, cycles and spurs (sturdier on noisy scans)")
    p.add_argument("--raw", action="store_true", help="the algorithm's curve as it is, not repaired (the "
                   "paper's toolbox exactly with --method cao)")
    p.add_argument("--log", metavar="F", help="write the repair's edit log (JSON; replay with skelcore edit)")
    p.add_argument("--quiet", action="store_true", help="do not print progress")
    p.set_defaults(func=run_skeletonize_cli)
    return p


def run_skeletonize_cli(args: argparse.Namespace) -> int:
    from .. import io
    from ..io.writers import curve_loss, write_curve, write_point_set
    from ..skeleton import skeletonize
    from .outputs import checked_outputs

    try:
        if not (args.out_skeletal or args.out_curve):
            raise SkelInputError("nothing to write: give --out-skeletal and/or --out-curve")
        if args.log and (args.raw or not args.out_curve):
            raise SkelInputError("--log is the repair's edit log: it needs --out-curve and no --raw")
        checked_outputs([("--out-skeletal", args.out_skeletal, "points"), ("--out-curve", args.out_curve, "curve"),
                         ("--log", args.log, "any")], (args.cloud,))
        cloud = io.load_cloud(args.cloud)
        progress = stderr_progress(args.quiet)
        choice = None
        if args.method == "cao" and not args.raw:
            from ..skeleton.default import default_skeleton

            skeletal, curve, info, choice = default_skeleton(cloud, progress=progress)
        else:
            skeletal, curve, info = skeletonize(cloud, progress=progress, return_info=True, method=args.method)
        clear_progress_line(progress)
        repaired = None
        if args.out_curve and not args.raw:
            repaired = _repaired(cloud, curve, progress)
        out = curve if repaired is None else repaired.curve
        loss = curve_loss(args.out_curve, out) if args.out_curve else None
        if loss:  # known only now (a cycle for SWC): refused before anything is written
            raise SkelInputError(f"{loss}; name a .ply, .json or .graphml file", args.out_curve)
        if args.out_skeletal:
            write_point_set(args.out_skeletal, skeletal, inputs=(args.cloud,))
        if args.out_curve:
            write_curve(args.out_curve, out, inputs=(args.cloud,))
        if args.log and repaired is not None:
            from ..edit import write_log

            write_log(args.log, repaired.log, (args.cloud,))
    except SkelInputError as exc:
        print(f"skelcore: error: {exc}", file=sys.stderr)
        return 2
    if choice is not None and choice.method == "axis":
        print(f"thin parts: cao's sampling ball is {choice.ratio:.1f} local thicknesses ({choice.thickness:.4g} units); "
              f"the axis curve at the cloud's spacing ({choice.spacing:.4g}) is taken instead")
    print(f"{len(cloud)} points contracted ({info.method}) in {info.iterations} iterations ({info.stop_reason}); "
          f"curve: {curve.n_vertices} vertices, {curve.n_edges} edges; {info.timings['total']:.2f} s")
    if repaired is not None:
        from .repair import repair_summary

        print(f"repaired: {repair_summary(repaired)}; curve: {repaired.curve.n_vertices} vertices, "
              f"{repaired.curve.n_edges} edges; {repaired.seconds:.2f} s")
    return 0


def _repaired(cloud, curve, progress):
    """The curve repaired from its defects; a curve the repair refuses (no edges, in pieces beyond
    ``repair_max_components``) is written as the algorithm gave it, and the refusal is printed. The
    repair evaluates the curve without the skeletal set: none of its findings uses it, and scoring it
    is most of a first evaluation's time (docs/repair.md "The real suite")."""
    from ..skeleton_repair import repair

    if curve.n_edges == 0:
        print("not repaired: the curve has no edges", file=sys.stderr)
        return None
    try:
        result = repair(cloud, curve, progress=progress)  # the curve alone: same findings, faster
    except SkelInputError as exc:
        print(f"not repaired: {exc}", file=sys.stderr)
        return None
    clear_progress_line(progress)
    return result
