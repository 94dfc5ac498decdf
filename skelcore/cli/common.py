"""Pieces every ``skelcore`` subcommand shares: the terminal progress line, argument types, the
Params built from ``--set`` and ``--boundedness-method``, and the paper's results table."""

from __future__ import annotations

import argparse
import math
import sys

from ..errors import SkelInputError
from ..params import Params

__all__ = ["format_table", "format_reference", "print_warnings", "stderr_progress", "params_from_args",
           "positive_int", "positive_float", "nonnegative_float", "clear_progress_line"]


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
    cov = summary.get("coverage")
    if cov is not None:
        rows.append(("coverage*", _coverage_cell(cov["skeletal"]), _coverage_cell(cov["curve"])))
    widths = [max(len(r[i]) for r in rows) for i in range(3)]
    lines = []
    for k, r in enumerate(rows):
        lines.append("  ".join(c.ljust(w) for c, w in zip(r, widths)).rstrip())
        if k == 0:
            lines.append("  ".join("-" * w for w in widths))
    if topo is not None:
        lines.append(f"(eps* = {_fmt_score(topo['eps_star'], 5)}, K = {topo['n_bars']} bars compared)")
    if cov is not None:
        lines.append(f"(* SkelScope's own, not the paper's: covered fraction of the cloud (slack s = "
                     f"{cov['slack']:g}, tau = {_fmt_score(cov['tau'], 4)}), mean / max gap, normalized units)")
    return "\n".join(lines)


def _coverage_cell(block: dict | None) -> str:
    if block is None:
        return "-"
    return f"{_fmt_score(block['fraction'])} (gap {_fmt_score(block['mean_gap'], 4)} / {_fmt_score(block['max_gap'], 4)})"


def format_reference(ref: dict) -> str:
    """The comparison with a reference curve, two lines."""
    counts = ", ".join(f"{k} {ref[k][0]}/{ref[k][1]}" for k in ("junctions", "endpoints", "components", "cycles"))
    return (f"reference curve: chamfer {_fmt_score(ref['chamfer'], 4)}, hausdorff {_fmt_score(ref['hausdorff'], 4)}, "
            f"precision {_fmt_score(ref['precision'])}, recall {_fmt_score(ref['recall'])}, F1 {_fmt_score(ref['f1'])} "
            f"(within tau = {_fmt_score(ref['tau'], 4)})\n"
            f"  graph (ours/reference): {counts}")


def print_warnings(warnings: list[dict]) -> None:
    """One stderr line per trust warning: ``skelcore: warning [code]: message``."""
    for w in warnings:
        print(f"skelcore: warning [{w['code']}]: {w['message']}", file=sys.stderr)


def stderr_progress(quiet: bool):
    """A ``progress(fraction, stage)`` that redraws one terminal line, or None when not a terminal."""
    if quiet or not sys.stderr.isatty():
        return None

    def progress(fraction: float, stage: str) -> None:
        print(f"\r{fraction * 100:5.1f}%  {stage[:40]:<40}", end="", file=sys.stderr, flush=True)

    return progress


def clear_progress_line(progress, width: int = 50) -> None:
    """Erase the progress line (after the work, before the table is printed)."""
    if progress is not None:
        print("\r" + " " * width + "\r", end="", file=sys.stderr)


def params_from_args(args: argparse.Namespace) -> Params:
    try:
        params = Params().with_strings(getattr(args, "set", None) or [])
        if getattr(args, "boundedness_method", None):
            params = params.replace(boundedness_method=args.boundedness_method)
    except ValueError as exc:
        raise SkelInputError(str(exc)) from None
    return params


def positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
    return value


def positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {text!r}")
    return value


def nonnegative_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not (math.isfinite(value) and value >= 0):
        raise argparse.ArgumentTypeError(f"expected a number >= 0, got {text!r}")
    return value
