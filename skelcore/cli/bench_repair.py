"""``skelcore bench repair DIR|samples --out FILE``: the repair measured on a benchmark folder
(:mod:`skelcore.benchmark.repair_bench`, docs/repair.md "Measured")."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from ..errors import SkelInputError

__all__ = ["register_repair", "run_bench_repair_cli"]


def register_repair(actions: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Add the ``repair`` action to ``skelcore bench``."""
    p = actions.add_parser(
        "repair",
        help="the repair measured: each tool's curve on every case, GT F1 and defect warnings before and after",
        description="Skeletonize every case of a benchmark folder (skelcore bench make, any suite) with each "
        "tool, repair the curve (skelcore repair) and score both against the case's reference: GT F1, the "
        "defect warnings and tallies before and after, the seconds of the skeletonization and of the repair. "
        "On a generated suite's clean tube cases also the reference with one controlled defect. SOURCE "
        "'samples' is the bundled samples (their LBC curves too). Writes FILE (JSON rows) and FILE with "
        "the suffix .md (the table and the summary); prints the summary.",
    )
    p.add_argument("source", metavar="DIR|samples", help="a benchmark folder, or 'samples'")
    p.add_argument("--out", required=True, metavar="FILE", help="the rows as JSON; the table and summary beside "
                   "it as FILE.md")
    p.add_argument("--tools", nargs="+", default=["cao", "skelscope"], metavar="NAME",
                   help="cao, skelscope, default (what skelcore skeletonize starts from: cao, or the axis curve on thin "
                   "parts) and the adapters pygel, kimimaro, skimage (default: cao skelscope)")
    p.add_argument("--cases", nargs="+", default=[], metavar="PATTERN", help="only cases whose names match a "
                   "shell pattern (e.g. '*_100k__clean')")
    p.add_argument("--set", dest="settings", action="append", default=[], metavar="TOOL.NAME=VALUE",
                   help="an adapter parameter, e.g. pygel.spacing=20 (repeatable)")
    p.add_argument("--no-defects", action="store_true", help="skip the references with a controlled defect")
    p.add_argument("--quiet", action="store_true", help="no line per job")
    p.set_defaults(func=run_bench_repair_cli)
    return p


def _settings(items: list[str], tools: list[str]) -> dict[str, dict[str, object]]:
    out: dict[str, dict[str, object]] = {}
    for item in items:
        key, sep, value = item.partition("=")
        tool, dot, name = key.partition(".")
        if not (sep and dot and name) or tool not in tools:
            raise SkelInputError(f"--set {item!r}: write TOOL.NAME=VALUE for one of the --tools")
        try:
            out.setdefault(tool, {})[name] = json.loads(value)
        except json.JSONDecodeError:
            out.setdefault(tool, {})[name] = value
    return out


def run_bench_repair_cli(args: argparse.Namespace) -> int:
    from .. import io
    from ..adapters import KINDS, require
    from ..benchmark.repair_bench import BUILT_IN, run_repair_bench
    from ..benchmark.repair_table import markdown_table, summary_lines

    try:
        for tool in args.tools:
            if tool not in BUILT_IN + KINDS:
                raise SkelInputError(f"unknown tool {tool!r} (known: {', '.join(BUILT_IN + KINDS)})")
            if tool in KINDS:
                require(tool)
        params = _settings(args.settings, args.tools)
        md = Path(args.out).with_suffix(".md")
        source = [] if args.source == "samples" else [args.source]
        io.atomic.check_output_file(args.out, source)
        io.atomic.check_output_file(md, source)

        done: list[dict] = []

        def progress(row: dict) -> None:
            done.append(row)  # the rows so far, rewritten after each job: a long run cut off keeps them
            with io.atomic.atomic_open(args.out, "w", inputs=source) as fh:
                json.dump(done, fh, indent=1)
            if not args.quiet:
                after = row.get("f1_after", row.get("failed") or row.get("refused"))
                held = f" (held {row['held_f1_before']} -> {row.get('held_f1_after', '-')})" if "held_f1_before" in row else ""
                print(f"{row['case']} {row['job']}: GT F1 {row.get('f1_before', '-')} -> {after}{held}", file=sys.stderr,
                      flush=True)

        rows = run_repair_bench(args.source, args.tools, only=args.cases, defects=not args.no_defects,
                                params=params, progress=progress)
        if not rows:
            raise SkelInputError("no case matches --cases", args.source)
    except SkelInputError as exc:
        print(f"skelcore: error: {exc}", file=sys.stderr)
        return 2
    lines = summary_lines(rows)
    with io.atomic.atomic_open(args.out, "w", inputs=source) as fh:
        json.dump(rows, fh, indent=1)
    with io.atomic.atomic_open(md, "w", inputs=source) as fh:
        fh.write(markdown_table(rows) + "\n" + "\n".join(f"- {line}" for line in lines) + "\n")
    print("\n".join(lines))
    print(f"{len(rows)} jobs: {args.out}, {md}")
    return 0
