"""``skelcore compare``: rank skeletonizers over a dataset.

``manifest`` (parse and check the TOML), ``jobs`` (one keyed job: degrade, skeletonize, evaluate),
``conditions``, ``methods``, ``backends`` (serial, process pool, Dask), ``job_store`` (resumable
per-job records), ``results_csv`` (results.csv), ``leaderboard``, ``profiles``, ``render``, ``report``
(report.html), ``figure`` (the graphic table), ``run_compare`` (all of it, end to end),
and ``finished_run`` (a finished run read back, for the viewer; a job's whole Evaluation is saved and
read by :mod:`skelcore.io.evaluation_files`).
"""

from .manifest import Manifest, load_manifest
from .run_compare import CompareResult, run_compare
from .backends import Backend, parse_backend

__all__ = ["Manifest", "load_manifest", "CompareResult", "run_compare", "Backend", "parse_backend"]
