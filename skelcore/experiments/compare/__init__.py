"""Deprecated alias of :mod:`skelcore.compare` (the compare subsystem moved there, its modules renamed);
removed in the next release. ``skelcore.experiments.compare.X`` still imports the module X now names."""

import importlib
import sys
import warnings

from ...compare import *  # noqa: F401,F403
from ...compare import __all__  # noqa: F401

warnings.warn("skelcore.experiments.compare is deprecated: import from skelcore.compare", DeprecationWarning,
              stacklevel=2)

_RENAMED = {"runner": "backends", "store": "job_store", "stored": "skelcore.io.evaluation_files", "results": "results_csv",
            "run": "run_compare", "run_folder": "finished_run", **{m: m for m in (
                "conditions", "figure", "jobs", "leaderboard", "manifest", "methods", "profiles", "render",
                "report")}}
for _old, _new in _RENAMED.items():
    sys.modules[f"{__name__}.{_old}"] = importlib.import_module(_new if "." in _new else f"skelcore.compare.{_new}")
