"""``skelcore repair CLOUD --curve C [--skeletal S] --out-curve C2 [--out-skeletal S2] [--log F] [--lossy]``: repair
a curve skeleton from the judge's findings (docs/repair.md) and write the repaired curve, the repaired
skeletal set and the edit log (replayable with ``skelcore edit``). Without --curve the curve is
extracted from S. Never overwrites a file nor an input; refuses in one line naming the file (exit 2) a
curve without edges, one in another frame (saying how to map it), one of too many components."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

__all__ = ["register", "run_repair"]


def register(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add ``skelcore repair``."""
    p = subparsers.add_parser(
        "repair", help="repair a curve skeleton from its defects (prune, cut, delete, join), never worse",
        description="Evaluate CURVE against CLOUD, act on the defects found (spurious branches pruned, edges "
        "outside the shape deleted, spurious cycles cut at their weakest edge, components joined inside the "
        "shape), keep each action only when nothing gets worse, and write the repaired curve to C2 (its "
        "extension picks the format), with --out-skeletal the repaired skeletal set (one row per cloud row) and, "
        "with --log, the edit log of what was done and why (docs/repair.md). Without --curve the curve is "
        "extracted from the skeletal set S (the cao skeletonizer's curve step) and repaired. "
        "C2, S2 and F must not exist yet.")
    p.add_argument("cloud", metavar="CLOUD", help="the point cloud")
    p.add_argument("--curve", metavar="C", help="the curve skeleton to repair (else extracted from S)")
    p.add_argument("--skeletal", metavar="S",
                   help="the skeletal point set, one row per cloud row (scored alongside; without --curve the "
                   "curve is extracted from it)")
    p.add_argument("--out-curve", metavar="C2", required=True, help="the repaired curve to write (a new file)")
    p.add_argument("--out-skeletal", metavar="S2",
                   help="the repaired skeletal set to write, one row per cloud row (a new file; docs/repair.md)")
    p.add_argument("--log", metavar="F", help="the edit log to write (JSON, a new file)")
    p.add_argument("--out-extracted", metavar="C0", help="without --curve: write the curve extracted from S, the "
                   "one the log starts from (skelcore edit C0 --ops F replays it; a new file)")
    p.add_argument("--lossy", action="store_true", help="write C2 even when its format loses something of the "
                   "repaired curve (a cycle in SWC, radii in OBJ); else that is refused, nothing written")
    p.add_argument("--quiet", action="store_true", help="no progress line")
    p.set_defaults(func=run_repair)
    return p


def run_repair(args: argparse.Namespace) -> int:
    from .. import io
    from ..edit import write_log
    from ..errors import SkelInputError
    from ..io.correspondence_files import load_skeletal
    from ..io.writers import curve_loss, write_curve, write_point_set
    from ..skeleton_repair import repair
    from ..skeleton_repair.from_skeletal import HOW
    from ..skeleton_repair.skeletal_out import repaired_skeletal
    from .common import clear_progress_line, stderr_progress
    from .outputs import checked_outputs

    if not (args.curve or args.skeletal):
        raise SkelInputError("nothing to repair: give --curve and/or --skeletal")
    if args.out_extracted and args.curve:
        raise SkelInputError("--out-extracted writes the curve extracted from --skeletal: it goes without --curve")
    out = Path(args.out_curve)
    inputs = tuple(p for p in (args.cloud, args.curve, args.skeletal) if p)
    outs = checked_outputs([("--out-curve", args.out_curve, "curve"), ("--out-skeletal", args.out_skeletal, "points"),
                            ("--log", args.log, "any"), ("--out-extracted", args.out_extracted, "curve")],
                           inputs, new=True)
    cloud = io.load_cloud(args.cloud)
    skeletal = None
    if args.skeletal:
        skeletal, index, _fmt = load_skeletal(args.skeletal, cloud)
        if index is not None or len(skeletal) != len(cloud):
            raise SkelInputError(f"repair takes a skeletal set with one row per cloud row ({len(skeletal)} rows, "
                                 f"the cloud has {len(cloud)})", args.skeletal)
    curve = io.load_curve(args.curve) if args.curve else None
    if curve is None:
        replay = "" if args.out_extracted or not args.log else \
            "; the log replays on that curve: --out-extracted C0 writes it"
        print(f"skelcore: {args.skeletal}: no --curve: the curve was extracted from the skeletal set by {HOW}{replay}",
              file=sys.stderr)
    progress = stderr_progress(args.quiet)
    try:
        result = repair(cloud, curve, skeletal=skeletal, progress=progress)
    except SkelInputError as exc:  # a refused curve (no edges, too many pieces, another frame): name it
        clear_progress_line(progress)
        if exc.path is not None:
            raise
        raise SkelInputError(_refusal(str(exc), args.curve or args.skeletal), args.curve or args.skeletal) from None
    clear_progress_line(progress)
    if result.extracted:
        result.log["repair"]["extracted"] = f"the curve was extracted from the skeletal set {args.skeletal} by {HOW}"
    loss = curve_loss(out, result.curve)
    if loss and not args.lossy:  # known only now: the file would not hold the curve the log leads to
        raise SkelInputError(f"{loss} (give --lossy to write it anyway, or name a .ply or .json file)", out)
    loss = curve_loss(args.out_extracted, result.start) if args.out_extracted else None
    if loss:  # the log's hash is of the curve itself: a lossy copy would not replay
        raise SkelInputError(f"{loss}: the log would not replay on it; name a .ply or .json file", args.out_extracted)
    for path in outs:
        if path.exists():  # appeared while we worked
            raise SkelInputError("exists: refusing to overwrite it", path)
    write_curve(out, result.curve, inputs=inputs, lossy=True)
    moved = ""
    if args.out_skeletal:
        s2, n_moved = repaired_skeletal(cloud, result.start, result.curve, skeletal)
        write_point_set(args.out_skeletal, s2, inputs=inputs)
        moved = f"; {args.out_skeletal}: {len(s2)} skeletal points, {n_moved} moved onto the repaired curve"
    if args.log:
        write_log(args.log, result.log, inputs)
    if args.out_extracted:
        write_curve(args.out_extracted, result.start, inputs=inputs, lossy=True)
    start = args.curve or f"the curve of {args.skeletal}"
    first = result.start
    print(f"{start}: {first.n_vertices} vertices, {first.n_edges} edges; {repair_summary(result)} "
          f"({result.stopped}); {out}: {result.curve.n_vertices} vertices, {result.curve.n_edges} edges{moved}")
    return 0


def _refusal(message: str, path: str) -> str:
    """The repair's refusal, with the frame warning's remedy made a command: repair has no mapping flags,
    ``skelcore convert`` writes the skeleton mapped into the cloud's frame (docs/guide/cli.md)."""
    if "--skeleton-scale" not in message:
        return message
    p = Path(path)
    mapped = p.with_name(f"{p.stem}_mapped{p.suffix}")
    return (f"{message}; write it mapped with skelcore convert {path} {mapped} --skeleton-scale S --skeleton-offset "
            "X Y Z (a skeletal set too, with --as points), then repair that")


def repair_summary(result: Any) -> str:
    """A repair in words: the defect counts before and after, the actions kept and rejected."""
    before = {k: v for k, v in result.tally_before.items() if v}
    after = {k: v for k, v in result.tally_after.items() if v}
    return (f"defects {before or 'none'} -> {after or 'none'}; {result.accepted} action(s) kept, "
            f"{result.rejected} rejected")
