"""Real scans (docs/metrics.md 6): openings of the surface, viewpoint-aware scores, stray points, caps."""

from .capping import Caps, cap_openings
from .openings import Opening, find_openings
from .outliers import Outliers, find_outliers
from .scan_report import ScanReport
from .synthetic import seen_from, visible_from
from .viewpoint import seen_boundedness

__all__ = ["Opening", "find_openings", "Caps", "cap_openings", "Outliers", "find_outliers", "ScanReport",
           "seen_boundedness", "visible_from", "seen_from"]
