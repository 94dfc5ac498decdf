"""The ``skelcore`` entry point: one parser on which every subcommand module registers itself.

Exit codes: 0 success, 2 input error or unwritable output (one line on stderr), 3 a trust warning
under `evaluate --strict`, 1 when `convert` reads back something else than it wrote, 130 interrupted.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from typing import Sequence

from ..errors import SkelInputError
from . import bench, compare, convert, edit, evaluate, figure, repair, skeletonize, study

__all__ = ["build_parser", "main"]

DESCRIPTION = "skelcore command line: evaluate a skeleton against its cloud; print the paper's table."
SUBCOMMANDS = (evaluate, study, skeletonize, compare, figure, convert, edit, repair, bench)


def build_parser() -> argparse.ArgumentParser:
    from ..version import __version__

    parser = argparse.ArgumentParser(prog="skelcore", description=DESCRIPTION)
    parser.add_argument("--version", action="version", version=f"skelcore {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for module in SUBCOMMANDS:
        module.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    def one_line_warning(message, category, filename, lineno, file=None, line=None):  # noqa: ARG001
        print(f"skelcore: warning: {message}", file=sys.stderr)

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("default")
            warnings.showwarning = one_line_warning
            return int(args.func(args) or 0)
    except SkelInputError as exc:
        print(f"skelcore: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("skelcore: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
