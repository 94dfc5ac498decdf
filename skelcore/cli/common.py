"""Pieces every ``skelcore`` subcommand shares: the terminal progress line, argument types, the
Params built from ``--set`` and ``--boundedness-method``, and the paper's results table."""

from __future__ import annotations

import argparse
import math
import sys
from typing import Callable, Iterable, Iterator, Sequence

from ..errors import SkelInputError
from ..params import Params
from ..display.summary_table import format_defects, format_table  # re-exported: the CLI's tables
from ..scores import Scores, format_score

__all__ = ["format_table", "format_defects", "format_reference", "format_ground_truth", "print_warnings", "stderr_progress", "params_from_args",
           "positive_int", "nonnegative_int", "positive_float", "nonnegative_float", "clear_progress_line",
           "LazyChoices"]


def format_reference(scores: Scores | dict) -> str:
    """The comparison with a reference curve, two lines (a :class:`Scores`, or the JSON ``reference`` block)."""
    s = scores if isinstance(scores, Scores) else Scores.from_json_dict({"reference": scores})
    counts = ", ".join(f"{k} {getattr(s, f'reference_{k}')[0]}/{getattr(s, f'reference_{k}')[1]}"
                       for k in ("junctions", "endpoints", "components", "cycles"))
    return (f"reference curve: chamfer {s.text('reference_chamfer')}, hausdorff {s.text('reference_hausdorff')}, "
            f"precision {s.text('reference_precision')}, recall {s.text('reference_recall')}, "
            f"F1 {s.text('reference_f1')} (within tau = {s.text('reference_tau')})\n"
            f"  graph (ours/reference): {counts}")


def format_ground_truth(block: dict) -> str:
    """The "ground truth" block under the paper's table (docs/metrics.md 5.3.1): the
    ``ground_truth`` block of the ``--json`` document (``GroundTruthComparison.to_dict()``)."""
    s = Scores.from_json_dict({"ground_truth": block})
    b = block
    source = {"reference": "the reference's file", "cloud": "estimated from the cloud",
              "reference+cloud": "the reference's file, estimated from the cloud where unknown"}.get(
        b["radius_source"], b["radius_source"])

    def node(kind: str) -> str:
        ours, ref, matched = b[f"{kind}s"]
        return (f"{kind}s P {s.text(f'gt_{kind}_precision')} R {s.text(f'gt_{kind}_recall')} "
                f"(ours {ours}, reference {ref}, matched {matched})")

    thresholds = b["thresholds"]
    return "\n".join([
        f"ground truth (local radius r: {source}):",
        f"  chamfer {s.text('gt_chamfer')} = {s.text('gt_chamfer_radii')} r (ours -> reference "
        f"{format_score(b['chamfer_to_reference'], 4)}, reference -> ours {format_score(b['chamfer_from_reference'], 4)})",
        f"  precision {s.text('gt_precision')}, recall {s.text('gt_recall')}, F1 {s.text('gt_f1')} (mean over "
        f"{len(thresholds)} thresholds {thresholds[0]:g}..{thresholds[-1]:g} r)",
        f"  {node('junction')}; {node('endpoint')}; within {b['match_radii']:g} r",
        f"  cycles {b['cycles'][0]} / {b['cycles'][1]} (error {b['cycle_error']:+d}); length ratio "
        f"{s.text('gt_length_ratio')}; branches {b['branches'][0]} / {b['branches'][1]}: {b['splits']} split(s), "
        f"{b['merges']} merge(s)",
        *_held_line(b),
    ])


def _held_line(b: dict) -> list[str]:
    """The scores on the held reference (docs/metrics.md 5.3.1), when the reference's facts were given."""
    if b.get("held_f1") is None:
        return []
    held, total = b["held_nodes"]
    return [f"  held reference (nodes at most {b['held_radii']:g} r outside the cloud's surface: {held} of {total}, "
            f"{100 * b['held_share']:.1f} % of its length): precision {format_score(b['held_precision'], 3)}, recall "
            f"{format_score(b['held_recall'], 3)}, F1 {format_score(b['held_f1'], 3)}"]


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


def _whole_number(text: str, least: int, what: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < least:
        raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}")
    return value


class LazyChoices(Sequence[str]):
    """An argument's ``choices`` read from their module when argparse first needs them (a value to check,
    the help's ``%(choices)s``): building the parser then imports no subcommand's engine. ``skelcore bench
    calibrate``'s suites and conditions live with the calibration, whose import (scipy.stats, the benchmark
    package) was about 1.1 CPU s of every ``skelcore`` start (docs/performance.md 6.13)."""

    def __init__(self, load: Callable[[], Iterable[str]]) -> None:
        self._load = load
        self._names: tuple[str, ...] | None = None

    def _all(self) -> tuple[str, ...]:
        if self._names is None:
            self._names = tuple(self._load())
        return self._names

    def __getitem__(self, i):  # type: ignore[override]
        return self._all()[i]

    def __len__(self) -> int:
        return len(self._all())

    def __iter__(self) -> Iterator[str]:
        return iter(self._all())

    def __contains__(self, value: object) -> bool:
        return value in self._all()


def positive_int(text: str) -> int:
    return _whole_number(text, 1, "a positive number")


def nonnegative_int(text: str) -> int:
    """A seed or a count that may be 0."""
    return _whole_number(text, 0, "a number >= 0")


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
