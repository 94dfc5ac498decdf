"""The ``skelcore`` command line: ``main`` and one module per subcommand (evaluate, skeletonize, study).

No engine module imports this package; it imports the engine.
"""

from .common import format_table, stderr_progress
from .main import build_parser, main

__all__ = ["main", "build_parser", "format_table", "stderr_progress"]
