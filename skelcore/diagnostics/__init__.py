"""Diagnostics: a skeleton's defects found without a reference skeleton, located, sized in
scale-free units and turned into warnings (issue 22; docs/diagnostics.md)."""

from .missing_parts import MissingParts, MissingRegion, missing_parts, skeleton_elements

__all__ = ["MissingParts", "MissingRegion", "missing_parts", "skeleton_elements"]
