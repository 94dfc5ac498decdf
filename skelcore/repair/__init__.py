"""Repair of a curve skeleton from the judge's findings (docs/repair.md): prune spurious branches,
delete edges outside the shape, cut spurious cycles, join components, each action kept only when it
makes nothing worse, all written as a replayable edit log with the reason of each operation.
The package is callable: ``skelcore.repair(cloud, curve, ...)`` is :func:`repair`."""

import sys as _sys
import types as _types

from .proposals import Action
from .run import RepairResult, repair

__all__ = ["repair", "RepairResult", "Action"]


class _CallableModule(_types.ModuleType):
    """The package and its function share the name ``repair``: calling the package calls the function."""

    def __call__(self, *args, **kwargs):
        return repair(*args, **kwargs)


_sys.modules[__name__].__class__ = _CallableModule
