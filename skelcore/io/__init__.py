"""Readers and writers for clouds, skeletal point sets and curve skeletons.

The format is detected from the file's content first (PLY, NPY/NPZ, JSON, PCD, OFF and .cg have a
recognisable start) and from its extension otherwise, so a ``.txt`` that is really a PLY loads as a
PLY. Every loader returns float64 coordinates in the file's own units (docs/metrics.md 0: normalization happens
later), remembers the path so that no writer can overwrite it (:func:`atomic.protect`), and turns
any problem into a one-line :class:`~skelcore.errors.SkelInputError` naming the file.
"""

from . import atomic  # noqa: F401  (skelcore.io.atomic is public)
from .loaders import SUPPORTED_EXTENSIONS, Loaded, detect_format, load_any, load_cloud, load_curve, load_points
from .pcd import pcd_viewpoint
from .ply import write_curve_ply, write_points_ply
from .writers import write_curve, write_point_set, write_points_npy, write_points_xyz

__all__ = [
    "Loaded",
    "load_any",
    "load_cloud",
    "load_points",
    "load_curve",
    "detect_format",
    "write_points_ply",
    "write_curve_ply",
    "write_points_xyz",
    "write_points_npy",
    "write_curve",
    "write_point_set",
    "pcd_viewpoint",
    "SUPPORTED_EXTENSIONS",
]
