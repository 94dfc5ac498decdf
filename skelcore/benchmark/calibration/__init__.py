"""Precision and recall of every warning code against ground truth: ``skelcore bench calibrate``.

Known defects are injected into the exact skeletons of the generated shapes (``synthetic``) and into
the traced SWC skeletons of the shipped neurons (``real``), under each scan condition, and every
skeleton is evaluated; each warning code's verdict is counted against a truth defined from what the
suite knows (docs/diagnostics.md "Precision and recall per warning"). Modules: ``grid`` (tasks and
skeleton kinds), ``skeletons`` (the kinds made), ``truth`` (the truth per code), ``pieces_truth``
(``disconnected``'s: a curve's pieces against its reference's), ``runner`` (tasks on the pool,
resume), ``calib_tables`` (counts, Wilson intervals, CSV and markdown, the docs block).
"""

from .grid import CODES, CONDITIONS, SUITES, Task, calibration_tasks
from .calib_tables import summary_rows, write_report
from .runner import run_calibration, run_task

__all__ = ["CODES", "CONDITIONS", "SUITES", "Task", "calibration_tasks", "summary_rows", "write_report",
           "run_calibration", "run_task"]
