"""Repair of a curve skeleton from the judge's findings (docs/repair.md): prune spurious branches,
delete edges outside the shape, cut spurious cycles, join components, each action kept only when it
makes nothing worse, all written as a replayable edit log with the reason of each operation.
``skelcore.repair`` is :func:`repair` (the package has another name, so the function keeps its own)."""

from .proposals import Action
from .run import RepairResult, repair

__all__ = ["repair", "RepairResult", "Action"]
