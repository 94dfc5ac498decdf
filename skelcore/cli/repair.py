"""``skelcore repair CLOUD --curve C [--skeletal S] --out-curve C2 [--log F]``: repair a curve skeleton
from the judge's findings (docs/repair.md) and write the repaired curve and the edit log (replayable
with ``skelcore edit``). Never overwrites a file nor an input; refuses in one line (exit 2) a curve
without edges, one in another frame, one of too many components."""

from __future__ import annotations

import argparse
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
        "extension picks the format) and, with --log, the edit log of what was done and why (docs/repair.md). "
        "C2 and F must not exist yet.")
    p.add_argument("cloud", metavar="CLOUD", help="the point cloud")
    p.add_argument("--curve", metavar="C", required=True, help="the curve skeleton to repair")
    p.add_argument("--skeletal", metavar="S", help="the skeletal point set (optional; scored alongside)")
    p.add_argument("--out-curve", metavar="C2", required=True, help="the repaired curve to write (a new file)")
    p.add_argument("--log", metavar="F", help="the edit log to write (JSON, a new file)")
    p.add_argument("--quiet", action="store_true", help="no progress line")
    p.set_defaults(func=run_repair)
    return p


def _new_file(path: Path, inputs: tuple[str, ...]) -> None:
    from ..errors import SkelInputError
    from ..io.atomic import check_not_input, check_output_file

    check_not_input(path, inputs)
    if path.exists():
        raise SkelInputError("exists: refusing to overwrite it", path)
    check_output_file(path, inputs)


def run_repair(args: argparse.Namespace) -> int:
    from .. import io
    from ..edit import write_log
    from ..errors import SkelInputError
    from ..io.correspondence_files import load_skeletal
    from ..io.writers import CURVE_SUFFIXES, write_curve
    from ..skeleton_repair import repair
    from .common import clear_progress_line, stderr_progress

    out = Path(args.out_curve)
    inputs = tuple(p for p in (args.cloud, args.curve, args.skeletal) if p)
    if out.suffix.lower() not in CURVE_SUFFIXES:
        raise SkelInputError(f"no curve writer for {out.suffix or '(no extension)'} "
                             f"(writable: {', '.join(CURVE_SUFFIXES)})", out)
    _new_file(out, inputs)
    if args.log:
        if Path(args.log).resolve() == out.resolve():
            raise SkelInputError("--log and --out-curve name the same file", args.log)
        _new_file(Path(args.log), inputs)
    cloud = io.load_cloud(args.cloud)
    curve = io.load_curve(args.curve)
    skeletal = load_skeletal(args.skeletal, cloud)[0] if args.skeletal else None
    progress = stderr_progress(args.quiet)
    result = repair(cloud, curve, skeletal=skeletal, progress=progress)
    clear_progress_line(progress)
    for path in (out, Path(args.log) if args.log else None):
        if path is not None and path.exists():  # appeared while we worked
            raise SkelInputError("exists: refusing to overwrite it", path)
    write_curve(out, result.curve, inputs=inputs, lossy=True)
    if args.log:
        write_log(args.log, result.log, inputs)
    print(f"{args.curve}: {curve.n_vertices} vertices, {curve.n_edges} edges; {repair_summary(result)} "
          f"({result.stopped}); {out}: {result.curve.n_vertices} vertices, {result.curve.n_edges} edges")
    return 0


def repair_summary(result: Any) -> str:
    """A repair in words: the defect counts before and after, the actions kept and rejected."""
    before = {k: v for k, v in result.tally_before.items() if v}
    after = {k: v for k, v in result.tally_after.items() if v}
    return (f"defects {before or 'none'} -> {after or 'none'}; {result.accepted} action(s) kept, "
            f"{result.rejected} rejected")
