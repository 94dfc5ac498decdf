"""Side panels: summary table with thresholds, barcodes, histogram, display controls, settings."""

from .barcode import BarcodePanel
from .display import DisplayPanel
from .histogram import HistogramPanel
from .pick import PickPanel
from .settings import SettingsPanel
from .summary import SummaryPanel

__all__ = ["BarcodePanel", "DisplayPanel", "HistogramPanel", "PickPanel", "SettingsPanel", "SummaryPanel"]
