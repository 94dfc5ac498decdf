"""``skelcore compare``: rank skeletonizers over a dataset (issue 9).

``manifest`` (parse and check the TOML), ``jobs`` (one keyed job: degrade, skeletonize, evaluate),
``conditions``, ``methods``, ``runner`` (serial, process pool, Dask), ``store`` (resumable per-job
records), ``results`` (results.csv), ``leaderboard``, ``profiles``, ``render``, ``report``
(report.html), ``figure`` (the graphic table), ``run`` (all of it, end to end), ``stored`` (a job's
whole Evaluation in its npz) and ``run_folder`` (a finished run read back, for the viewer).
"""

from .manifest import Manifest, load_manifest
from .run import CompareResult, run_compare
from .runner import Backend, parse_backend

__all__ = ["Manifest", "load_manifest", "CompareResult", "run_compare", "Backend", "parse_backend"]
