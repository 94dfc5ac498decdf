"""Defects of a skeleton found without a reference skeleton (issue 22; docs/diagnostics.md): its
branches and cycle basis, spurious branches, spurious and missing cycles, parts outside the shape."""

from .branches import JUNCTION, Branches, decompose_branches, densify

__all__ = ["JUNCTION", "Branches", "decompose_branches", "densify"]
