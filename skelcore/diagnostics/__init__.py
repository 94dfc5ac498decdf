"""Defects of a skeleton found without a reference skeleton (issue 22; docs/diagnostics.md): its
branches and cycle basis, spurious branches, spurious and missing cycles, parts outside the shape,
missing parts and completeness."""

from .branches import JUNCTION, Branches, decompose_branches, densify
from .cycles import CycleDefects, find_cycle_defects
from .defects import CurveDefects, find_curve_defects
from .interior import VoxelShape, betti_numbers, median_spacing, voxelize_interior
from .missing_parts import MissingParts, MissingRegion, missing_parts, skeleton_elements
from .outside import OutsideDefects, find_outside
from .spurs import SpurDefects, find_spurious_branches

__all__ = [
    "JUNCTION", "Branches", "decompose_branches", "densify",
    "SpurDefects", "find_spurious_branches",
    "CycleDefects", "find_cycle_defects",
    "OutsideDefects", "find_outside",
    "CurveDefects", "find_curve_defects",
    "VoxelShape", "voxelize_interior", "betti_numbers", "median_spacing",
    "MissingParts", "MissingRegion", "missing_parts", "skeleton_elements",
]
