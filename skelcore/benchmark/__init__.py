"""Benchmarks with ground truth: generated shapes with exact curve skeletons and radii
(``families``, ``tubes``), uniform surface samples (``surface_sampling``), graded scan effects
(``scan_effects``), the suites (``suite``), the folder's files (``writer``, ``reference_ply``) and
``make_benchmark`` (``generate``), behind ``skelcore bench make DIR``; the traced neurons as real
shapes with ground truth (``neurons``, ``real_suite``)."""

from .families import FAMILIES, make_shape
from .generate import BenchResult, make_benchmark
from .reference_ply import ReferenceCurve, read_reference
from .scan_effects import Scan, ScanEffects, scan
from .suite import SUITES, suite_cases
from .surface_sampling import SurfacePoints, SurfaceSampler
from .tubes import BenchShape, Plate, Tube, reference_skeleton, signed_distance

__all__ = ["FAMILIES", "make_shape", "BenchResult", "make_benchmark", "ReferenceCurve", "read_reference",
           "Scan", "ScanEffects", "scan", "SUITES", "suite_cases", "SurfacePoints", "SurfaceSampler",
           "BenchShape", "Plate", "Tube", "reference_skeleton", "signed_distance"]
