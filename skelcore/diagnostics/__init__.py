"""Defects of a skeleton found without a reference skeleton (docs/diagnostics.md): its
branches and cycle basis, spurious branches, spurious and missing cycles, parts outside the shape,
missing parts and completeness; the trust checks (``trust``) and the warning record (``trust_warning``).

The names below are imported on first use, so that importing ``skelcore.diagnostics.trust_warning``
(the foundation's record) loads none of the diagnostics. ``missing_parts`` is both a module and its
function: the package keeps the function (as an eager import did)."""

from __future__ import annotations

import importlib
import sys
import types

__all__ = [
    "JUNCTION", "Branches", "decompose_branches", "densify",
    "SpurDefects", "find_spurious_branches",
    "CycleDefects", "find_cycle_defects",
    "OutsideDefects", "find_outside",
    "CurveDefects", "find_curve_defects",
    "VoxelShape", "voxelize_interior", "betti_numbers", "wide_tunnels", "median_spacing",
    "MissingParts", "MissingRegion", "missing_parts", "skeleton_elements",
]
_LAZY = {**dict.fromkeys(("JUNCTION", "Branches", "decompose_branches", "densify"), "branches"),
         **dict.fromkeys(("SpurDefects", "find_spurious_branches"), "spurs"),
         **dict.fromkeys(("CycleDefects", "find_cycle_defects"), "cycles"),
         **dict.fromkeys(("OutsideDefects", "find_outside"), "outside"),
         **dict.fromkeys(("CurveDefects", "find_curve_defects"), "defects"),
         **dict.fromkeys(("VoxelShape", "voxelize_interior", "betti_numbers", "wide_tunnels", "median_spacing"), "interior"),
         **dict.fromkeys(("MissingParts", "MissingRegion", "missing_parts", "skeleton_elements"), "missing_parts")}


def __getattr__(name: str):
    if name not in _LAZY:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
    globals()[name] = value
    return value


class _Package(types.ModuleType):
    def __setattr__(self, name: str, value) -> None:
        if name == "missing_parts" and isinstance(value, types.ModuleType):  # the import system naming the
            value = value.missing_parts  # submodule on its package: the package keeps the function
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package
