"""``skelcore edit CURVE --ops LOG --out NEW``: replay an edit log on a curve skeleton and write the
edited curve (its format by NEW's extension). Never overwrites a file; a log made for another
skeleton, an unknown operation or an id out of range is refused in one line (exit 2)."""

from __future__ import annotations

import argparse
from pathlib import Path

__all__ = ["register", "run_edit"]


def register(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add ``skelcore edit CURVE --ops LOG --out NEW [--lossy]``."""
    p = subparsers.add_parser(
        "edit",
        help="replay an edit log (delete, add, split, merge, move, prune, cut) on a curve skeleton",
        description="Read CURVE (any curve format skelcore reads), apply the operations of the edit log LOG "
        "(docs/output_formats.md, \"The edit log\"; made for this very curve: its skeleton_hash) and write "
        "the edited curve to NEW, whose extension picks the format (.ply .obj .swc .cg .graphml .json). "
        "NEW must not exist yet.",
    )
    p.add_argument("curve", metavar="CURVE", help="the curve skeleton the log was made for")
    p.add_argument("--ops", metavar="LOG", required=True, help="the edit log (JSON)")
    p.add_argument("--out", metavar="NEW", required=True, help="the edited curve to write (a new file)")
    p.add_argument("--lossy", action="store_true", help="write even when NEW's format loses something "
                   "(radii in OBJ, a cycle in SWC)")
    p.set_defaults(func=run_edit)
    return p


def run_edit(args: argparse.Namespace) -> int:
    from ..edit import read_log, replay
    from ..errors import SkelInputError
    from ..io import load_curve
    from ..io.writers import curve_loss, write_curve
    from .outputs import checked_outputs

    out, inputs = Path(args.out), (args.curve, args.ops)
    checked_outputs([("--out", args.out, "curve")], inputs, new=True)
    curve = load_curve(args.curve)
    log = read_log(args.ops)
    try:
        edited, changes = replay(curve, log)
    except SkelInputError as exc:  # the log's fault: name it, and the curve it was replayed on
        if exc.path is not None:
            raise
        raise SkelInputError(f"{exc}; the curve: {args.curve}", args.ops) from None
    loss = curve_loss(out, edited)
    if loss and not args.lossy:
        raise SkelInputError(f"{loss} (give --lossy to write anyway)", out)
    if out.exists():  # appeared while we worked
        raise SkelInputError("exists: refusing to overwrite it", out)
    write_curve(out, edited, inputs=inputs, lossy=args.lossy)
    print(f"{args.curve}: {curve.n_vertices} vertices, {curve.n_edges} edges; {len(changes)} operation(s) -> "
          f"{out}: {edited.n_vertices} vertices, {edited.n_edges} edges")
    return 0
